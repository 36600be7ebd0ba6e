// Wall-clock benchmarks (Google Benchmark) of the cycle's kernels and the whole cycle, with the
// obvious OpenCV segmentation as the baseline in the same run. Run: build/host/bin/harmoloc-bench.
// Instruction counts (deterministic) come from harmoloc-instructions under callgrind instead.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "bench_fixtures.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/particle_filter.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "opencv_reference.hpp"

namespace {

using namespace harmoloc;

// Frames per resolution, rendered once. Segmentation benchmarks take (width, height) as args.
const bench::Frames& frames_at(std::uint32_t width, std::uint32_t height) {
  static std::map<std::pair<std::uint32_t, std::uint32_t>, std::unique_ptr<bench::Frames>> cache;
  auto& slot = cache[{width, height}];
  if (!slot) slot = std::make_unique<bench::Frames>(bench::simulated_frames(width, height, 8));
  return *slot;
}

const bench::Frames& frames_of(const benchmark::State& state) {
  return frames_at(static_cast<std::uint32_t>(state.range(0)),
                   static_cast<std::uint32_t>(state.range(1)));
}

void set_pixels(benchmark::State& state, const bench::Frames& f) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * f.width_px * f.height_px);
}

// Runs @p segment(frame bytes, areas) over the frames of the benchmark's resolution, one frame
// per iteration, and reports pixels per second.
template <typename Segment>
void segment_frames(benchmark::State& state, const bench::Frames& f, bool yuyv, Segment&& segment) {
  const auto& images = yuyv ? f.yuyv : f.rgb;
  algorithms::AreaVector areas;
  std::size_t i = 0;
  for (auto _ : state) {
    segment(f, images[i++ % images.size()].data(), areas);
    benchmark::DoNotOptimize(areas);
  }
  set_pixels(state, f);
}

// One table of each kind, rebuilt when a benchmark asks for another board count or path.
template <typename Table>
const Table& table_for(std::size_t boards, algorithms::SegmentPath path) {
  static std::vector<std::uint8_t> storage(algorithms::MaskTable::kStorageBytes);
  static Table table;
  static std::size_t built_for = 0;
  if (!table.ready() || built_for != boards) {
    table.build(algorithms::BoardClassifier(bench::board_thresholds(boards)), storage.data());
    built_for = boards;
  }
  table.set_path(path);
  return table;
}

constexpr int kBest = -1;  // path argument: best_segment_path()

algorithms::SegmentPath path_arg(std::int64_t arg) {
  return arg == kBest ? algorithms::best_segment_path() : static_cast<algorithms::SegmentPath>(arg);
}

// Args: width, height, path (kBest or a SegmentPath), boards.
bool skip_unsupported(benchmark::State& state, algorithms::SegmentPath path) {
  if (algorithms::segment_path_supported(path)) return false;
  state.SkipWithError("path not supported on this CPU");
  return true;
}

void BM_SegmentRgb24Table(benchmark::State& state) {
  const algorithms::SegmentPath path = path_arg(state.range(2));
  if (skip_unsupported(state, path)) return;
  state.SetLabel(algorithms::segment_path_name(path));
  const auto& table =
      table_for<algorithms::ColourTable>(static_cast<std::size_t>(state.range(3)), path);
  segment_frames(state, frames_of(state), false,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   algorithms::segment_rgb24(data, f.width_px, f.height_px, f.width_px * 3, table,
                                             a);
                 });
}

void BM_SegmentYuyvTable(benchmark::State& state) {
  const algorithms::SegmentPath path = path_arg(state.range(2));
  if (skip_unsupported(state, path)) return;
  state.SetLabel(algorithms::segment_path_name(path));
  const auto& table =
      table_for<algorithms::YuyvTable>(static_cast<std::size_t>(state.range(3)), path);
  segment_frames(state, frames_of(state), true,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   algorithms::segment_yuyv(data, f.width_px, f.height_px, f.width_px * 2, table,
                                            a);
                 });
}

// The worst case for a table: a frame of noise, every pixel a different, random entry (a cache
// miss a pixel). Args: path (kBest or a SegmentPath), 0 RGB24 / 1 YUYV; 640x480, 6 boards.
void BM_SegmentNoiseTable(benchmark::State& state) {
  const algorithms::SegmentPath path = path_arg(state.range(0));
  if (skip_unsupported(state, path)) return;
  const bool yuyv = state.range(1) != 0;
  state.SetLabel(std::string(algorithms::segment_path_name(path)) + (yuyv ? " yuyv" : " rgb24"));
  constexpr std::uint32_t kW = 640, kH = 480;
  static std::vector<std::uint8_t> noise = [] {
    std::vector<std::uint8_t> bytes(kW * kH * 3);
    std::uint64_t x = 88172645463325252ULL;
    for (auto& b : bytes) {
      x ^= x << 13U;
      x ^= x >> 7U;
      x ^= x << 17U;
      b = static_cast<std::uint8_t>(x);
    }
    return bytes;
  }();
  algorithms::AreaVector areas;
  if (yuyv) {
    const auto& table = table_for<algorithms::YuyvTable>(6, path);
    for (auto _ : state) {
      algorithms::segment_yuyv(noise.data(), kW, kH, kW * 2, table, areas);
      benchmark::DoNotOptimize(areas);
    }
  } else {
    const auto& table = table_for<algorithms::ColourTable>(6, path);
    for (auto _ : state) {
      algorithms::segment_rgb24(noise.data(), kW, kH, kW * 3, table, areas);
      benchmark::DoNotOptimize(areas);
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kW * kH);
}

void BM_SegmentYuyvDecode(benchmark::State& state) {
  const auto& table = table_for<algorithms::ColourTable>(6, algorithms::SegmentPath::kScalar);
  segment_frames(state, frames_of(state), true,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   algorithms::segment_yuyv(data, f.width_px, f.height_px, f.width_px * 2, table,
                                            a);
                 });
}

void BM_SegmentRgb24(benchmark::State& state) {
  const algorithms::BoardClassifier classifier(bench::board_thresholds());
  segment_frames(state, frames_of(state), false,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   algorithms::segment_rgb24(data, f.width_px, f.height_px, f.width_px * 3,
                                             classifier, a);
                 });
}

void BM_SegmentRgb24OpenCV(benchmark::State& state) {
  cv::setNumThreads(1);
  const auto thresholds = bench::board_thresholds();
  reference::OpencvScratch scratch;
  segment_frames(state, frames_of(state), false,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   reference::opencv_segment_rgb24(
                       data, static_cast<int>(f.width_px), static_cast<int>(f.height_px),
                       static_cast<int>(f.width_px * 3), thresholds, a, scratch);
                 });
}

void BM_SegmentYuyvOpenCV(benchmark::State& state) {
  cv::setNumThreads(1);
  const auto thresholds = bench::board_thresholds();
  reference::OpencvScratch scratch;
  segment_frames(state, frames_of(state), true,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   reference::opencv_segment_yuyv(
                       data, static_cast<int>(f.width_px), static_cast<int>(f.height_px),
                       static_cast<int>(f.width_px * 2), thresholds, a, scratch);
                 });
}

// Eq. 9 over a synthetic map of state.range(0) samples; @p ridge > 0: with the local linear
// correction (a map whose training chose it), the extra normal equations over the neighbours
// the kernel reaches.
// @p columns: with the boards' centroid columns (map format 12) in the kernel's distance.
void harmonic_query_bench(benchmark::State& state, float ridge, bool columns = false) {
  static algorithms::MapFile map;
  bench::synthetic_map(static_cast<std::size_t>(state.range(0)), 320, 240, map);
  map.model.local_linear_ridge = ridge;
  map.model.column_weight = columns ? 1.0F : 0.0F;
  for (std::size_t i = 0; columns && i < map.model.sample_count; ++i) {
    for (std::size_t k = 0; k < map.model.feature_count; ++k)
      map.model.sample_columns(i)[k] =
          0.01F * (static_cast<float>((i * 7 + k * 13) % 41) - 20.0F) * map.model.sample(i)[k];
  }
  std::array<float, algorithms::HarmonicModel::kMaxFeatures> features{0.5F, 1.0F, 0.2F,
                                                                      1.5F, 0.3F, 0.8F};
  const algorithms::ColumnFeatures frame_columns{0.1F, -0.2F, 0.05F, 0.3F, -0.1F, 0.0F};
  for (auto _ : state) {
    features[0] += 1e-6F;
    benchmark::DoNotOptimize(
        algorithms::harmonic_query(map.model, features, columns ? &frame_columns : nullptr));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
}

void BM_HarmonicQuery(benchmark::State& state) {
  harmonic_query_bench(state, 0.0F);
}

void BM_HarmonicQueryLocalLinear(benchmark::State& state) {
  harmonic_query_bench(state, 0.01F);
}

void BM_HarmonicQueryColumns(benchmark::State& state) {
  harmonic_query_bench(state, 0.0F, true);
}

void BM_FilterStep(benchmark::State& state) {
  static algorithms::ParticleFilter filter;
  filter.configure(static_cast<std::size_t>(state.range(0)), 1, algorithms::MotionNoise{});
  filter.initialize(algorithms::Pose2{2.0, 1.0, 1.5}, 0.05, 0.1, false);
  for (auto _ : state) {
    filter.predict(algorithms::OdometryDelta{0.0033, 0.001});
    filter.update_position(2.0, 1.0, 0.04, 0.05);
    filter.resample_if_needed(1.1);  // always: the worst case
    benchmark::DoNotOptimize(filter.estimate());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
}

// The default filter step: predict, the per-board robust update against the forward map (with
// its assessment at the estimate), resampling (always: the worst case) and the estimate.
void BM_FilterStepBoards(benchmark::State& state) {
  static algorithms::MapFile map;
  bench::synthetic_map(204, 320, 240, map);
  static algorithms::ParticleFilter filter;
  filter.configure(static_cast<std::size_t>(state.range(0)), 1, algorithms::MotionNoise{});
  filter.initialize(algorithms::Pose2{2.1, 1.0, 1.5}, 0.05, 0.1, false);
  const algorithms::BoardModelParams params;
  algorithms::BoardReliability reliability;
  reliability.reset(params);
  algorithms::BoardFeatures observed;
  bench::bench_observation(map.forward, observed);
  algorithms::BoardUpdate update;
  for (auto _ : state) {
    filter.predict(algorithms::OdometryDelta{0.0033, 0.001});
    reliability.assess(map.forward, observed, filter.mean_pose(), params, update);
    benchmark::DoNotOptimize(filter.update_boards(update));
    filter.resample_if_needed(1.1);
    benchmark::DoNotOptimize(filter.estimate());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
}

// Args: width, height, pixel format (0 RGB24, 1 YUYV), boards, particles, map samples.
void BM_WholeCycle(benchmark::State& state) {
  const bench::Frames& f = frames_of(state);
  const auto format = static_cast<hal::PixelFormat>(state.range(2));
  static algorithms::MapFile map;
  bench::synthetic_map(static_cast<std::size_t>(state.range(5)), f.width_px, f.height_px, map,
                       static_cast<std::size_t>(state.range(3)));
  firmware::FirmwareConfig config = firmware::default_config();
  config.filter.particles = static_cast<std::size_t>(state.range(4));
  bench::MemoryCamera camera(f, format);
  bench::MemoryEncoders encoders;
  bench::NullLink link;
  bench::StepClock clock;
  auto cycle = std::make_unique<firmware::LocalizationCycle>(config, map, camera, encoders, link,
                                                             clock, format);
  for (int i = 0; i < 30; ++i) cycle->run_once();  // past initialisation into the steady state
  for (auto _ : state) benchmark::DoNotOptimize(cycle->run_once());
  set_pixels(state, f);
}

// Resolutions of the scaling table (docs/performance.md).
void resolutions(benchmark::internal::Benchmark* b) {
  for (const auto& r : {std::pair{320, 240}, std::pair{640, 480}, std::pair{1280, 720}})
    b->Args({r.first, r.second});
}

// Segmentation with a table: the best path and the scalar one at every resolution (6 boards),
// then the best path at 640x480 for 1..8 boards.
void table_args(benchmark::internal::Benchmark* b) {
  const int scalar = static_cast<int>(algorithms::SegmentPath::kScalar);
  for (int path : {kBest, scalar}) {
    for (const auto& r : {std::pair{320, 240}, std::pair{640, 480}, std::pair{1280, 720}})
      b->Args({r.first, r.second, path, 6});
  }
  for (int boards = 1; boards <= 8; ++boards) {
    if (boards != 6) b->Args({640, 480, kBest, boards});  // 6 is above
  }
}

void cycle_args(benchmark::internal::Benchmark* b) {
  for (const auto& r : {std::pair{320, 240}, std::pair{640, 480}, std::pair{1280, 720}}) {
    for (int format : {0, 1}) b->Args({r.first, r.second, format, 6, 1024, 204});
  }
  for (int boards : {1, 2, 4, 8}) b->Args({640, 480, 0, boards, 1024, 204});
  for (int particles : {256, 4096}) b->Args({640, 480, 0, 6, particles, 204});
  for (int samples : {1024, 4096}) b->Args({640, 480, 0, 6, 1024, samples});
}

BENCHMARK(BM_SegmentRgb24Table)->Apply(table_args)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentYuyvTable)->Apply(table_args)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentNoiseTable)
    ->ArgsProduct({{kBest, static_cast<int>(algorithms::SegmentPath::kScalar)}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentYuyvDecode)->Apply(resolutions)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentRgb24)->Apply(resolutions)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentRgb24OpenCV)->Apply(resolutions)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentYuyvOpenCV)->Apply(resolutions)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HarmonicQuery)->Arg(204)->Arg(1024)->Arg(4096)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HarmonicQueryLocalLinear)
    ->Arg(204)
    ->Arg(1024)
    ->Arg(4096)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HarmonicQueryColumns)->Arg(204)->Arg(1024)->Arg(4096)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FilterStep)->Arg(256)->Arg(1024)->Arg(4096)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FilterStepBoards)->Arg(256)->Arg(1024)->Arg(4096)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WholeCycle)->Apply(cycle_args)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
