// The scene simulator's rendering speed (docs/scenarios.md): one frame of desk-shuttle at
// 320x240, 640x480 and 1280x720 (the same field of view, so the same scene at more pixels), the
// robot at poses spread along its route; the true areas (visible_board_pixels) at 320x240; and
// random scenes (random_scene.hpp) at their own resolutions. Time per frame and per pixel (items
// per second: pixels).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/route.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"

namespace hs = harmoloc::sim_host;
namespace ha = harmoloc::algorithms;

namespace {

constexpr std::size_t kPoses = 32;

std::vector<ha::Pose2> poses_along(const hs::Scenario& s) {
  ha::Pcg32 rng(7, 1);
  const auto motion = hs::simulate_motion(s, 0.01, rng, nullptr);
  std::vector<ha::Pose2> poses;
  for (std::size_t i = 0; i < kPoses; ++i)
    poses.push_back(motion[(i * 2 + 1) * motion.size() / (2 * kPoses)].pose);
  return poses;
}

hs::Scenario scene(const char* name, std::int64_t width, std::int64_t height) {
  hs::Scenario s = hs::load_scenario(name);
  s.camera.width_px = static_cast<std::uint32_t>(width);
  s.camera.height_px = static_cast<std::uint32_t>(height);
  return s;
}

void render_scene(benchmark::State& state, const hs::Scenario& s, double at_s) {
  hs::SceneRenderer renderer(s);
  renderer.set_time(at_s);
  const std::vector<ha::Pose2> poses = poses_along(s);
  ha::Pcg32 rng(1, 2);
  std::vector<std::uint8_t> rgb;
  std::size_t i = 0;
  for (auto _ : state) {
    renderer.render(poses[i++ % kPoses], rng, rgb);
    benchmark::DoNotOptimize(rgb.data());
  }
  state.SetItemsProcessed(state.iterations() * s.camera.width_px * s.camera.height_px);
}

void BM_RenderDesk(benchmark::State& state) {
  render_scene(state, scene("desk-shuttle", state.range(0), state.range(1)), 0.0);
}

// desk-occlusion while the person stands in front of the green board (a cylinder in view).
void BM_RenderDeskOccluded(benchmark::State& state) {
  render_scene(state, scene("desk-occlusion", state.range(0), state.range(1)), 31.0);
}

void BM_VisibleBoardPixels(benchmark::State& state) {
  const hs::Scenario s = scene("desk-shuttle", state.range(0), state.range(1));
  const hs::SceneRenderer renderer(s);
  const std::vector<ha::Pose2> poses = poses_along(s);
  std::size_t i = 0;
  for (auto _ : state) {
    auto counts = renderer.visible_board_pixels(poses[i++ % kPoses]);
    benchmark::DoNotOptimize(counts.data());
  }
  state.SetItemsProcessed(state.iterations() * s.camera.width_px * s.camera.height_px);
}

// Random scenes: seed 5 is 320x240 (shuttle, 3 boards), 4 is 640x480 (shuttle, 8 boards), 1 is
// 1280x720 (loop, 8 boards, two on stands).
void BM_RenderRandom(benchmark::State& state) {
  render_scene(state, hs::random_scenario(static_cast<std::uint64_t>(state.range(0))), 0.0);
}

void resolutions(benchmark::internal::Benchmark* b) {
  b->Args({320, 240})->Args({640, 480})->Args({1280, 720});
}

}  // namespace

BENCHMARK(BM_RenderDesk)->Apply(resolutions)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderDeskOccluded)->Args({320, 240})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VisibleBoardPixels)->Args({320, 240})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderRandom)->Arg(5)->Arg(4)->Arg(1)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
