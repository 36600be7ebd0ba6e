// Wall-clock benchmarks (Google Benchmark) of the cycle's kernels and the whole cycle, with the
// obvious OpenCV segmentation as the baseline in the same run. Run: build/host/bin/harmoloc-bench.
// Instruction counts (deterministic) come from harmoloc-instructions under callgrind instead.
#include <benchmark/benchmark.h>

#include <memory>
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

const bench::Frames& frames_at(std::uint32_t width) {
  static std::unique_ptr<bench::Frames> cache[3];
  const int slot = width == 320 ? 0 : width == 640 ? 1 : 2;
  if (!cache[slot])
    cache[slot] = std::make_unique<bench::Frames>(bench::simulated_frames(width, width * 3 / 4, 8));
  return *cache[slot];
}

void set_pixels(benchmark::State& state, const bench::Frames& f) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * f.width_px * f.height_px);
}

// Runs @p segment(frame bytes, areas) over the frames of the benchmark's resolution, one frame
// per iteration, and reports pixels per second.
template <typename Segment>
void segment_frames(benchmark::State& state, bool yuyv, Segment&& segment) {
  const bench::Frames& f = frames_at(static_cast<std::uint32_t>(state.range(0)));
  const auto& images = yuyv ? f.yuyv : f.rgb;
  algorithms::AreaVector areas;
  std::size_t i = 0;
  for (auto _ : state) {
    segment(f, images[i++ % images.size()].data(), areas);
    benchmark::DoNotOptimize(areas);
  }
  set_pixels(state, f);
}

const algorithms::ColourTable& colour_table() {
  static std::vector<std::uint8_t> storage(algorithms::ColourTable::kEntries);
  static algorithms::ColourTable table;
  if (!table.ready())
    table.build(algorithms::BoardClassifier(firmware::default_config().thresholds), storage.data());
  return table;
}

void BM_SegmentRgb24(benchmark::State& state) {
  const algorithms::BoardClassifier classifier(firmware::default_config().thresholds);
  segment_frames(state, false,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   algorithms::segment_rgb24(data, f.width_px, f.height_px, f.width_px * 3,
                                             classifier, a);
                 });
}

void BM_SegmentRgb24Table(benchmark::State& state) {
  const algorithms::ColourTable& table = colour_table();
  segment_frames(state, false,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   algorithms::segment_rgb24(data, f.width_px, f.height_px, f.width_px * 3, table,
                                             a);
                 });
}

void BM_SegmentRgb24OpenCV(benchmark::State& state) {
  cv::setNumThreads(1);
  const auto thresholds = firmware::default_config().thresholds;
  reference::OpencvScratch scratch;
  segment_frames(state, false,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   reference::opencv_segment_rgb24(
                       data, static_cast<int>(f.width_px), static_cast<int>(f.height_px),
                       static_cast<int>(f.width_px * 3), thresholds, a, scratch);
                 });
}

void BM_SegmentYuyv(benchmark::State& state) {
  const algorithms::ColourTable& table = colour_table();
  segment_frames(state, true,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   algorithms::segment_yuyv(data, f.width_px, f.height_px, f.width_px * 2, table,
                                            a);
                 });
}

void BM_SegmentYuyvOpenCV(benchmark::State& state) {
  cv::setNumThreads(1);
  const auto thresholds = firmware::default_config().thresholds;
  reference::OpencvScratch scratch;
  segment_frames(state, true,
                 [&](const bench::Frames& f, const std::uint8_t* data, algorithms::AreaVector& a) {
                   reference::opencv_segment_yuyv(
                       data, static_cast<int>(f.width_px), static_cast<int>(f.height_px),
                       static_cast<int>(f.width_px * 2), thresholds, a, scratch);
                 });
}

void BM_HarmonicQuery(benchmark::State& state) {
  static algorithms::MapFile map;
  bench::synthetic_map(static_cast<std::size_t>(state.range(0)), 320, 240, map);
  std::array<float, algorithms::HarmonicModel::kMaxFeatures> features{0.5F, 1.0F, 0.2F,
                                                                      1.5F, 0.3F, 0.8F};
  for (auto _ : state) {
    features[0] += 1e-6F;
    benchmark::DoNotOptimize(algorithms::harmonic_query(map.model, features));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * state.range(0));
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

void BM_WholeCycle(benchmark::State& state) {
  const bench::Frames& f = frames_at(static_cast<std::uint32_t>(state.range(0)));
  static algorithms::MapFile map;
  bench::synthetic_map(204, f.width_px, f.height_px, map);
  const firmware::FirmwareConfig config = firmware::default_config();
  bench::MemoryCamera camera(f);
  bench::MemoryEncoders encoders;
  bench::NullLink link;
  bench::StepClock clock;
  auto cycle =
      std::make_unique<firmware::LocalizationCycle>(config, map, camera, encoders, link, clock);
  for (auto _ : state) benchmark::DoNotOptimize(cycle->run_once());
  set_pixels(state, f);
}

BENCHMARK(BM_SegmentRgb24)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentRgb24Table)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentRgb24OpenCV)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentYuyv)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SegmentYuyvOpenCV)->Arg(320)->Arg(640)->Arg(1280)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HarmonicQuery)->Arg(204)->Arg(1024)->Arg(4096)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_FilterStep)->Arg(256)->Arg(1024)->Arg(4096)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WholeCycle)->Arg(320)->Arg(640)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
