// harmoloc-instructions KERNEL [ARG]: runs one kernel between callgrind's start/stop markers, so
// `valgrind --tool=callgrind --instr-atstart=no` counts exactly its instructions (deterministic,
// unlike time). Kernels: seg_table W, seg_table_yuyv W (the cycle's colour table), seg_rgb W (HSV
// arithmetic per pixel), seg_rgb_opencv W, seg_yuyv W, seg_yuyv_opencv W, harmonic N,
// filter N, cycle W. Each counts REPEAT runs after one warm-up run (divide by REPEAT).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <valgrind/callgrind.h>
#include <opencv2/core.hpp>

#include "bench_fixtures.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/particle_filter.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "opencv_reference.hpp"

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

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: harmoloc-instructions KERNEL ARG (see the source for the list)\n");
    return 2;
  }
  const std::string kernel = argv[1];
  const auto arg = static_cast<std::uint32_t>(std::strtoul(argv[2], nullptr, 10));
  cv::setNumThreads(1);
  const auto thresholds = firmware::default_config().thresholds;
  algorithms::AreaVector areas;
  if (kernel.rfind("seg_", 0) == 0 || kernel == "cycle") {
    const bench::Frames f = bench::simulated_frames(arg, arg * 3 / 4, 1);
    const algorithms::BoardClassifier classifier(thresholds);
    reference::OpencvScratch scratch;
    const int w = static_cast<int>(f.width_px), h = static_cast<int>(f.height_px);
    if (kernel == "seg_table") {
      static std::vector<std::uint8_t> storage(algorithms::ColourTable::kEntries);
      algorithms::ColourTable table;
      table.build(classifier, storage.data());
      measure([&] {
        algorithms::segment_rgb24(f.rgb[0].data(), f.width_px, f.height_px, f.width_px * 3, table,
                                  areas);
      });
    } else if (kernel == "seg_table_yuyv") {
      static std::vector<std::uint8_t> storage(algorithms::ColourTable::kEntries);
      algorithms::ColourTable table;
      table.build(classifier, storage.data());
      measure([&] {
        algorithms::segment_yuyv(f.yuyv[0].data(), f.width_px, f.height_px, f.width_px * 2, table,
                                 areas);
      });
    } else if (kernel == "seg_rgb") {
      measure([&] {
        algorithms::segment_rgb24(f.rgb[0].data(), f.width_px, f.height_px, f.width_px * 3,
                                  classifier, areas);
      });
    } else if (kernel == "seg_rgb_opencv") {
      measure([&] {
        reference::opencv_segment_rgb24(f.rgb[0].data(), w, h, w * 3, thresholds, areas, scratch);
      });
    } else if (kernel == "seg_yuyv") {
      measure([&] {
        algorithms::segment_yuyv(f.yuyv[0].data(), f.width_px, f.height_px, f.width_px * 2,
                                 classifier, areas);
      });
    } else if (kernel == "seg_yuyv_opencv") {
      measure([&] {
        reference::opencv_segment_yuyv(f.yuyv[0].data(), w, h, w * 2, thresholds, areas, scratch);
      });
    } else if (kernel == "cycle") {
      bench::synthetic_map(204, f.width_px, f.height_px, g_map);
      const firmware::FirmwareConfig config = firmware::default_config();
      bench::MemoryCamera camera(f);
      bench::MemoryEncoders encoders;
      bench::NullLink link;
      bench::StepClock clock;
      auto cycle = std::make_unique<firmware::LocalizationCycle>(config, g_map, camera, encoders,
                                                                 link, clock);
      for (int i = 0; i < 30; ++i) cycle->run_once();  // past initialisation into the steady state
      measure([&] { cycle->run_once(); });
    } else {
      std::fprintf(stderr, "unknown kernel %s\n", kernel.c_str());
      return 2;
    }
  } else if (kernel == "harmonic") {
    bench::synthetic_map(arg, 320, 240, g_map);
    const std::array<float, algorithms::HarmonicModel::kMaxFeatures> features{0.5F, 1.0F, 0.2F,
                                                                              1.5F, 0.3F, 0.8F};
    measure([&] { (void)algorithms::harmonic_query(g_map.model, features); });
  } else if (kernel == "filter") {
    static algorithms::ParticleFilter filter;
    filter.configure(arg, 1, algorithms::MotionNoise{});
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
