// harmoloc-instructions KERNEL ARG: runs one kernel between callgrind's start/stop markers, so
// `valgrind --tool=callgrind --instr-atstart=no` counts exactly its instructions (deterministic,
// unlike time). Each counts REPEAT runs after one warm-up run (divide by REPEAT). RES is WxH
// (or W alone for W x 3W/4) of a simulated frame.
//
//   seg_table RES              RGB24, colour table, the best path of this CPU (the cycle's)
//   seg_table_scalar RES       the same on the portable scalar path
//   seg_yuyv_table RES         YUYV, YUYV table, best path (the cycle's)
//   seg_yuyv_table_scalar RES  the same on the scalar path
//   seg_yuyv_decode RES        YUYV with the RGB table, each pixel decoded first
//   seg_table_noise RES        seg_table on a frame of uniform random bytes (every pixel another
//                              colour: the table's worst case for the caches)
//   seg_table_boards N         seg_table at 640x480 with N boards (1..8)
//   seg_yuyv_table_boards N    seg_yuyv_table at 640x480 with N boards
//   seg_rgb RES, seg_yuyv RES  the HSV arithmetic per pixel (BoardClassifier)
//   seg_rgb_opencv RES, seg_yuyv_opencv RES   the OpenCV reference
//   harmonic N                 harmonic query over N samples, 6 boards
//   harmonic_linear N          the same with the local linear correction (ridge 0.01)
//   fix_error_grid N           the fix term's lookup of the fix error near the fix's place (map
//                              format 11): one cell of the grid built at start-up over N samples
//   fix_error_grid_build N     building that grid at start-up (the benchmark map's 4224 cells)
//   filter N                   particle filter step with N particles
//   kidnap_preference R        the kidnap test's board preference over the places within R cm of
//                              a fix 60 cm along the route from the estimate (areas and bearings;
//                              only while a fix is that far)
//   kidnap_preference_areas R  the same from the areas alone
//   nearby_tables R            the nearby pose test's tables' evidence in a frame after a re-seed
//                              on a floor: two poses each refined over 5 x 5 places within R cm
//   cycle RES, cycle_yuyv RES  the whole cycle, steady state: 6 boards, 1024 particles, 204 samples
//   cycle_boards N, cycle_particles N, cycle_samples N   the whole cycle at 640x480 RGB24 with
//                              one of those changed
//   path 0                     prints the best segmentation path of this CPU (no measurement)
// Built without OpenCV (HARMOLOC_BENCH_OPENCV=0: the ARM builds, tests/bench/arm_instructions.sh)
// the OpenCV kernels are left out.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <valgrind/callgrind.h>
#if HARMOLOC_BENCH_OPENCV
#include <opencv2/core.hpp>
#endif

#include "bench_fixtures.hpp"
#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/fix_error_grid.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/nearby_pose_test.hpp"
#include "harmoloc/algorithms/particle_filter.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#if HARMOLOC_BENCH_OPENCV
#include "opencv_reference.hpp"
#endif

namespace {

using namespace harmoloc;
constexpr int kRepeat = 4;

template <typename F>
void measure(F&& run) {
  run();  // warm-up: first-touch page faults, lazy initialisation in libraries
  CALLGRIND_ZERO_STATS;
  CALLGRIND_START_INSTRUMENTATION;
  for (int i = 0; i < kRepeat; ++i) run();
  CALLGRIND_STOP_INSTRUMENTATION;
}

algorithms::MapFile g_map;

bool starts_with(const std::string& s, const char* prefix) {
  return s.rfind(prefix, 0) == 0;
}

// "640x480", or "640" for 640 x 480 (W x 3W/4).
void parse_resolution(const char* arg, std::uint32_t& w, std::uint32_t& h) {
  char* end = nullptr;
  w = static_cast<std::uint32_t>(std::strtoul(arg, &end, 10));
  h = *end == 'x' ? static_cast<std::uint32_t>(std::strtoul(end + 1, nullptr, 10)) : w * 3 / 4;
}

// A table of the kernel's kind (RGB or YUYV), built for @p boards and put on @p path.
template <typename Table>
const Table& table_for(std::size_t boards, algorithms::SegmentPath path) {
  static std::vector<std::uint8_t> storage(algorithms::MaskTable::kStorageBytes);
  static Table table;
  table.build(algorithms::BoardClassifier(bench::board_thresholds(boards)), storage.data());
  if (!table.set_path(path)) {
    std::fprintf(stderr, "path %s not supported here\n", algorithms::segment_path_name(path));
    std::exit(3);
  }
  return table;
}

// @p floor: the map read as a floor map (route terms off) with the floor search on
// (kidnap.floor_search, algorithms/floor_search.hpp): what it adds to a cycle.
int run_cycle(const bench::Frames& f, hal::PixelFormat format, std::size_t boards,
              std::size_t particles, std::size_t samples, bool floor = false, bool kld = false) {
  bench::synthetic_map(samples, f.width_px, f.height_px, g_map, boards);
  firmware::FirmwareConfig config = firmware::default_config();
  config.filter.particles = particles;
  if (floor) {
    config.observation.route_terms = firmware::RouteTerms::kOff;
    config.kidnap.floor_search = true;
  }
  // As filter.kld = "auto" does on a floor map (the synthetic map is not one by its calibration).
  if (kld) config.filter.kld_mode = firmware::KldMode::kOn;
  bench::MemoryCamera camera(f, format);
  bench::MemoryEncoders encoders;
  bench::NullLink link;
  bench::StepClock clock;
  auto cycle = std::make_unique<firmware::LocalizationCycle>(config, g_map, camera, encoders, link,
                                                             clock, format);
  for (int i = 0; i < 30; ++i) cycle->run_once();  // past initialisation into the steady state
  measure([&] { cycle->run_once(); });
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: harmoloc-instructions KERNEL ARG (see the source for the list)\n");
    return 2;
  }
  const std::string kernel = argv[1];
  if (kernel == "path") {  // not a kernel: the best segmentation path of this CPU
    std::printf("%s\n", algorithms::segment_path_name(algorithms::best_segment_path()));
    return 0;
  }
  const auto n = static_cast<std::size_t>(std::strtoul(argv[2], nullptr, 10));
#if HARMOLOC_BENCH_OPENCV
  cv::setNumThreads(1);
#endif
  algorithms::AreaVector areas;
  const algorithms::SegmentPath best = algorithms::best_segment_path();
  const algorithms::SegmentPath scalar = algorithms::SegmentPath::kScalar;

  if (starts_with(kernel, "seg_") || starts_with(kernel, "cycle")) {
    const bool by_count = kernel == "seg_table_boards" || kernel == "seg_yuyv_table_boards" ||
                          kernel == "cycle_boards" || kernel == "cycle_particles" ||
                          kernel == "cycle_samples";
    std::uint32_t w = 640, h = 480;
    if (!by_count) parse_resolution(argv[2], w, h);
    const bench::Frames f = bench::simulated_frames(w, h, 1);
    const std::size_t boards = kernel == "seg_table_boards" || kernel == "seg_yuyv_table_boards" ||
                                       kernel == "cycle_boards"
                                   ? n
                                   : 6;
    const auto thresholds = bench::board_thresholds(boards);
    const algorithms::BoardClassifier classifier(thresholds);
#if HARMOLOC_BENCH_OPENCV
    reference::OpencvScratch scratch;
#endif
    const std::uint8_t* rgb = f.rgb[0].data();
    const std::uint8_t* yuyv = f.yuyv[0].data();
    [[maybe_unused]] const int iw = static_cast<int>(w), ih = static_cast<int>(h);
    if (kernel == "seg_table" || kernel == "seg_table_scalar" || kernel == "seg_table_boards") {
      const auto& table =
          table_for<algorithms::ColourTable>(boards, kernel == "seg_table_scalar" ? scalar : best);
      measure([&] { algorithms::segment_rgb24(rgb, w, h, w * 3, table, areas); });
    } else if (kernel == "seg_yuyv_table" || kernel == "seg_yuyv_table_scalar" ||
               kernel == "seg_yuyv_table_boards") {
      const auto& table = table_for<algorithms::YuyvTable>(
          boards, kernel == "seg_yuyv_table_scalar" ? scalar : best);
      measure([&] { algorithms::segment_yuyv(yuyv, w, h, w * 2, table, areas); });
    } else if (kernel == "seg_table_noise") {
      std::vector<std::uint8_t> noise(std::size_t{w} * h * 3);
      algorithms::Pcg32 rng(7, 1);
      for (std::uint8_t& b : noise) b = static_cast<std::uint8_t>(rng.next_u32() >> 24);
      const auto& table = table_for<algorithms::ColourTable>(boards, best);
      measure([&] { algorithms::segment_rgb24(noise.data(), w, h, w * 3, table, areas); });
    } else if (kernel == "seg_yuyv_decode") {
      const auto& table = table_for<algorithms::ColourTable>(boards, scalar);
      measure([&] { algorithms::segment_yuyv(yuyv, w, h, w * 2, table, areas); });
    } else if (kernel == "seg_rgb") {
      measure([&] { algorithms::segment_rgb24(rgb, w, h, w * 3, classifier, areas); });
#if HARMOLOC_BENCH_OPENCV
    } else if (kernel == "seg_rgb_opencv") {
      measure([&] {
        reference::opencv_segment_rgb24(rgb, iw, ih, iw * 3, thresholds, areas, scratch);
      });
#endif
    } else if (kernel == "seg_yuyv") {
      measure([&] { algorithms::segment_yuyv(yuyv, w, h, w * 2, classifier, areas); });
#if HARMOLOC_BENCH_OPENCV
    } else if (kernel == "seg_yuyv_opencv") {
      measure([&] {
        reference::opencv_segment_yuyv(yuyv, iw, ih, iw * 2, thresholds, areas, scratch);
      });
#endif
    } else if (kernel == "cycle") {
      return run_cycle(f, hal::PixelFormat::kRgb24, 6, 1024, 204);
    } else if (kernel == "cycle_floor") {
      return run_cycle(f, hal::PixelFormat::kRgb24, 6, 1024, 204, true);
    } else if (kernel == "cycle_floor_kld") {
      return run_cycle(f, hal::PixelFormat::kRgb24, 6, 1024, 204, true, true);
    } else if (kernel == "cycle_yuyv") {
      return run_cycle(f, hal::PixelFormat::kYuyv, 6, 1024, 204);
    } else if (kernel == "cycle_boards") {
      return run_cycle(f, hal::PixelFormat::kRgb24, n, 1024, 204);
    } else if (kernel == "cycle_particles") {
      return run_cycle(f, hal::PixelFormat::kRgb24, 6, n, 204);
    } else if (kernel == "cycle_samples") {
      return run_cycle(f, hal::PixelFormat::kRgb24, 6, 1024, n);
    } else {
      std::fprintf(stderr, "unknown kernel %s\n", kernel.c_str());
      return 2;
    }
  } else if (kernel == "harmonic" || kernel == "harmonic_linear") {
    bench::synthetic_map(n, 320, 240, g_map);
    if (kernel == "harmonic_linear") g_map.model.local_linear_ridge = 0.01F;
    const std::array<float, algorithms::HarmonicModel::kMaxFeatures> features{0.5F, 1.0F, 0.2F,
                                                                              1.5F, 0.3F, 0.8F};
    measure([&] { (void)algorithms::harmonic_query(g_map.model, features); });
  } else if (kernel == "fix_error_grid" || kernel == "fix_error_grid_build") {
    bench::synthetic_map(n, 320, 240, g_map);
    for (std::size_t i = 0; i < n; ++i) g_map.model.fix_error_m[i] = 0.01F;
    static algorithms::FixErrorGrid grid;
    grid.build(g_map.model, g_map.forward);
    float e = 0.0F;
    if (kernel == "fix_error_grid")
      measure([&] { e += grid.at(g_map.forward, 2.1, 1.0); });
    else
      measure([&] { grid.build(g_map.model, g_map.forward); });
    if (!(grid.at(g_map.forward, 2.1, 1.0) > 0.0F)) return 1;
  } else if (kernel == "filter_boards" || kernel == "filter_boards_kld" ||
             kernel == "filter_boards_vis" || kernel == "filter_boards_proj" ||
             kernel == "filter_boards_proj_steady" || kernel == "filter_boards_proj_areas" ||
             kernel == "filter_boards_proj_areas_steady" ||
             kernel == "filter_boards_proj_areas_kld") {
    // The default measurement update: every board against the forward map, robust weights.
    // _kld: with KLD-sampling on a cloud as tight as in steady tracking (1 cm, 1 degree), n the
    // capacity: the count it settles at decides the cost (the bins' pass included).
    // _vis: on a floor map with visibility in every cell (harmoloc-train --visibility).
    // _proj: the same with every board's bearing projected from its outline (map version 15);
    // _proj_steady: on a cloud as tight as in steady tracking (1 cm, 0.5 degree), most particles
    // within the reach of the projection's quadratic about the estimate.
    // _proj_areas, _proj_areas_steady: the same with every board's area projected as well (map
    // version 17) from the eight-point outlines, the cloud's spreads given as the firmware does.
    // _proj_areas_kld: _proj_areas_steady with KLD-sampling (on by default on a floor map), n
    // the capacity: the floor filter's step in steady tracking.
    bench::synthetic_map(204, 320, 240, g_map);
    const bool floor_kld = kernel == "filter_boards_proj_areas_kld";
    const bool projected_areas = kernel == "filter_boards_proj_areas" ||
                                 kernel == "filter_boards_proj_areas_steady" || floor_kld;
    const bool steady = kernel == "filter_boards_proj_steady" ||
                        kernel == "filter_boards_proj_areas_steady" || floor_kld;
    const bool projected =
        kernel == "filter_boards_proj" || kernel == "filter_boards_proj_steady" || projected_areas;
    if (kernel == "filter_boards_vis" || projected) {
      if constexpr (!algorithms::ForwardMap::kHeadingTermStorage) {
        std::fprintf(stderr, "filter_boards_vis: this build keeps no visibility storage\n");
        return 2;
      }
      algorithms::ForwardMap& f = g_map.forward;
      f.has_visibility = true;
      f.visibility_angle_gain = 0.3F;
      for (std::size_t at = 0; at < f.stored_cells(); ++at)
        for (std::size_t b = 0; b < f.board_count; ++b) {
          float* t = f.heading_terms.data() + (at * algorithms::kMaxBoards + b) * 2;
          t[0] = 1.5F;   // the board's feature seen whole
          t[1] = 0.05F;  // its angular half-width
        }
      if (projected) bench::project_every_board(f, projected_areas);
    }
    static algorithms::ParticleFilter filter;
    filter.configure(n, 1, algorithms::MotionNoise{});
    if (kernel == "filter_boards_kld" || floor_kld) {
      algorithms::KldSampling kld;
      kld.enabled = true;
      filter.set_kld_sampling(kld);
      filter.initialize(algorithms::Pose2{2.1, 1.0, 1.5}, 0.01, 0.02, false);
    } else if (steady) {
      filter.initialize(algorithms::Pose2{2.1, 1.0, 1.5}, 0.01, 0.0087, false);
    } else {
      filter.initialize(algorithms::Pose2{2.1, 1.0, 1.5}, 0.05, 0.1, false);
    }
    const algorithms::BoardModelParams params;
    static algorithms::BoardReliability reliability;
    reliability.reset(params);
    algorithms::BoardFeatures observed;
    bench::bench_observation(g_map.forward, observed);
    static algorithms::BoardUpdate update;
    measure([&] {
      filter.predict(algorithms::OdometryDelta{0.0033, 0.001});
      if (projected_areas) {
        // As the firmware does where the map projects areas: the cloud's spreads widen the
        // areas' noise and set the reach of the quadratics (BoardUpdate::near_at).
        double yaw_var = 0.0, position_var = 0.0;
        const algorithms::Pose2 mean = filter.mean_pose(&yaw_var, &position_var);
        reliability.assess(g_map.forward, observed, mean, params, update, yaw_var,
                           std::sqrt(position_var), filter.size());
      } else {
        reliability.assess(g_map.forward, observed, filter.mean_pose(), params, update);
      }
      (void)filter.update_boards(update);
      filter.resample_if_needed(1.1);
      (void)filter.estimate();
    });
  } else if (kernel == "kidnap_preference" || kernel == "kidnap_preference_areas") {
    bench::synthetic_map(204, 320, 240, g_map);
    algorithms::BoardModelParams params;
    params.bearings = kernel == "kidnap_preference";
    algorithms::BoardFeatures observed;
    bench::bench_observation(g_map.forward, observed);
    const double reach_m = 0.01 * static_cast<double>(n);
    // The synthetic map's route runs along x = 2.1.
    measure([&] {
      (void)algorithms::board_preference_near(g_map.forward, observed, 2.1, 1.6, reach_m, 2.1, 1.0,
                                              reach_m, params);
    });
  } else if (kernel == "nearby_tables") {
    // The nearby pose test's tables' evidence in a hint frame after a re-seed on a floor: the
    // search's pose and the estimate each refined over 5 x 5 places within n cm.
    bench::synthetic_map(204, 320, 240, g_map);
    const algorithms::BoardModelParams params;
    algorithms::BoardFeatures observed;
    bench::bench_observation(g_map.forward, observed);
    const algorithms::FloorPose searched{2.1, 1.6, 1.5, 0.0, true};
    const algorithms::Pose2 estimate{2.1, 1.0, 1.5};
    const double radius_m = 0.01 * static_cast<double>(n);
    measure([&] {
      (void)algorithms::tables_evidence(g_map.forward, observed, searched, estimate, radius_m,
                                        params, 0U);
    });
  } else if (kernel == "filter") {
    static algorithms::ParticleFilter filter;
    filter.configure(n, 1, algorithms::MotionNoise{});
    filter.initialize(algorithms::Pose2{2.0, 1.0, 1.5}, 0.05, 0.1, false);
    measure([&] {
      filter.predict(algorithms::OdometryDelta{0.0033, 0.001});
      filter.update_position(2.0, 1.0, 0.04, 0.05);
      filter.resample_if_needed(1.1);
      (void)filter.estimate();
    });
  } else {
    std::fprintf(stderr, "unknown kernel %s\n", kernel.c_str());
    return 2;
  }
  std::printf("%u %u %u\n", areas.pixels[0], areas.pixels[1], static_cast<unsigned>(kRepeat));
  return 0;
}
