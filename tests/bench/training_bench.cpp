// Training speed (docs/training.md): the whole trainer on 204 samples (64 labelled + 140
// unlabelled, 6 boards) as harmoloc-train runs it after reading the areas: board selection,
// the cross-validated grid, the final solves and the known-place calibration; and the same
// without board selection, and with 1024 samples.
#include <benchmark/benchmark.h>

#include <cmath>
#include <memory>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/trainer.hpp"

namespace hs = harmoloc::sim_host;
namespace hd = harmoloc::dataset;
namespace ha = harmoloc::algorithms;

namespace {

// A run along a route driven forth and back: six board areas that change smoothly (and
// differently) with the position, with pixel noise; labels evenly spread.
struct Run {
  hs::AreaSeries areas;
  std::vector<hd::StampedPose> labels;
};

Run make_run(std::size_t frames, std::size_t labels) {
  Run r;
  r.areas.image_width_px = 320;
  r.areas.image_height_px = 240;
  ha::Pcg32 rng(11);
  const double t0 = 1767225600.0;
  for (std::size_t i = 0; i < frames; ++i) {
    const double u = static_cast<double>(i) / static_cast<double>(frames - 1);
    const double s = u < 0.5 ? 2.0 * u : 2.0 - 2.0 * u;  // forth and back
    const double x = 2.1 + 0.07 * std::sin(6.0 * s), y = 0.35 + 1.25 * s;
    ha::AreaVector a;
    a.count = 6;
    for (std::size_t k = 0; k < 6; ++k) {
      const double phase = 0.9 * static_cast<double>(k);
      const double v =
          900.0 + 700.0 * std::sin(2.5 * y + phase) * std::cos(4.0 * (x - 2.1) + phase) + 300.0 * y;
      a.pixels[k] = static_cast<std::uint32_t>(std::max(0.0, v + 6.0 * rng.normal()));
    }
    // Where the boards appear across the frame (a pinhole of 60 degrees, the robot facing
    // along the route, +y, reversing on the way back as add_odometry drives it): the column
    // sums the trainer learns the lens's law and the bearings from.
    const double heading = std::atan2(1.25, 0.42 * std::cos(6.0 * s));
    static constexpr double kBoardX[6] = {1.0, 1.6, 2.2, 2.8, 3.3, 2.1};
    static constexpr double kBoardY[6] = {3.5, 3.8, 4.0, 3.7, 3.4, 5.0};
    a.width_px = 320;
    for (std::size_t k = 0; k < 6; ++k) {
      const double angle = heading - std::atan2(kBoardY[k] - y, kBoardX[k] - x);
      const double t = std::tan(angle) / (2.0 * std::tan(0.5236)) + 0.002 * rng.normal();
      const double column = 159.5 + 320.0 * t;
      if (std::fabs(t) < 0.45)
        a.column_sum[k] = static_cast<std::uint64_t>(std::llround(column * a.pixels[k]));
      else
        a.side_pixels[k] = 1;  // cut by the frame's edge
    }
    const double t = t0 + static_cast<double>(i) / 30.0;
    r.areas.timestamp_ns.push_back(static_cast<std::uint64_t>(std::llround(t * 1e6)) * 1000ULL);
    r.areas.areas.push_back(a);
    if ((i * labels) % frames < labels) {
      hd::StampedPose p;
      p.t_s = static_cast<double>(r.areas.timestamp_ns.back() / 1000U) * 1e-6;
      p.pose = ha::Pose2{x, y, 1.57};
      r.labels.push_back(p);
    }
  }
  return r;
}

// The same run with wheel odometry (100 Hz, 2048 ticks a turn, 1% slip): what a robot records,
// as the trainer places every frame between the labels.
void add_odometry(Run& r) {
  ha::Pcg32 rng(12);
  const std::size_t frames = r.areas.areas.size();
  hs::OdometryTrack& o = r.areas.odometry;
  o.geometry.wheel_radius_m = 0.05;
  o.geometry.track_m = 0.3;
  o.geometry.ticks_per_rev = 2048;
  const double m_per_tick = 2.0 * 3.141592653589793 * 0.05 / 2048.0;
  const auto pose_at = [&](double i) {
    const double u = i / static_cast<double>(frames - 1);
    const double s = u < 0.5 ? 2.0 * u : 2.0 - 2.0 * u;
    return std::pair<double, double>{2.1 + 0.07 * std::sin(6.0 * s), 0.35 + 1.25 * s};
  };
  double left = 0.0, right = 0.0;
  double prev_x = pose_at(0).first, prev_y = pose_at(0).second, heading = 1.57;
  const std::uint64_t t0 = r.areas.timestamp_ns.front();
  const std::size_t steps = frames * 10 / 3;  // 100 Hz
  for (std::size_t k = 0; k <= steps; ++k) {
    const double i = static_cast<double>(k) * 0.3;
    const auto [x, y] = pose_at(std::min(i, static_cast<double>(frames - 1)));
    const double dx = x - prev_x, dy = y - prev_y;
    const double d = std::hypot(dx, dy);
    // Forward on the way out, reversing on the way back (the camera keeps facing the boards).
    const double sign = i / static_cast<double>(frames - 1) < 0.5 ? 1.0 : -1.0;
    double yaw = heading;
    if (d > 1e-9) yaw = std::atan2(sign * dy, sign * dx);
    const double dyaw = std::remainder(yaw - heading, 2.0 * 3.141592653589793);
    left += (sign * d - 0.15 * dyaw) * (1.0 + 0.01 * rng.normal()) / m_per_tick;
    right += (sign * d + 0.15 * dyaw) * (1.0 + 0.01 * rng.normal()) / m_per_tick;
    heading = yaw;
    prev_x = x;
    prev_y = y;
    o.timestamp_ns.push_back(t0 + static_cast<std::uint64_t>(k) * 10000000ULL);
    o.left_ticks.push_back(static_cast<std::int64_t>(std::floor(left)));
    o.right_ticks.push_back(static_cast<std::int64_t>(std::floor(right)));
  }
}

void train(benchmark::State& state, std::size_t frames, std::size_t labelled, int unlabelled,
           bool select) {
  const Run run = make_run(frames, labelled);
  hs::TrainOptions opt;
  opt.thresholds.count = 6;
  opt.use_odometry = false;  // Wu & Qin's labelled + unlabelled samples
  opt.unlabelled = unlabelled;
  opt.select_boards = select;
  auto map = std::make_unique<ha::MapFile>();
  for (auto _ : state) {
    const hs::TrainReport report = hs::train_on_areas(run.areas, run.labels, opt, *map);
    benchmark::DoNotOptimize(report.x.cv_rmse_m);
  }
  state.counters["samples"] = static_cast<double>(map->model.sample_count);
  state.counters["boards"] = static_cast<double>(map->model.feature_count);
}

// The figure: an area log of a 4000-frame run with 64 labels and its wheel odometry,
// every frame placed, board selection, the forward map and the calibration (<= 2 s).
void train_placed(benchmark::State& state, bool bearings, bool columns = true,
                  bool column_gain = false) {
  Run run = make_run(4000, 64);
  add_odometry(run);
  hs::TrainOptions opt;
  opt.thresholds.count = 6;
  opt.bearings = bearings;
  opt.column_features = columns;
  opt.column_gain = column_gain;
  auto map = std::make_unique<ha::MapFile>();
  for (auto _ : state) {
    const hs::TrainReport report = hs::train_on_areas(run.areas, run.labels, opt, *map);
    benchmark::DoNotOptimize(report.x.cv_rmse_m);
    state.counters["placed"] = report.placement.used ? 1.0 : 0.0;
    state.counters["bearing_ms"] = report.bearings_ms;
    state.counters["forward_ms"] = report.forward_ms;
    state.counters["bearing_cells"] = static_cast<double>(report.forward.bearing_cells);
    state.counters["column_weight"] = report.column_weight;
    state.counters["column_gain_observations"] =
        static_cast<double>(report.column_gain.observations);
  }
  state.counters["samples"] = static_cast<double>(map->model.sample_count);
}
void BM_TrainPlaced4000(benchmark::State& state) {
  train_placed(state, true);
}
// The same without the bearings in the map (harmoloc-train --no-bearings; the lens's law is
// still learnt and reported): what the bearings cost.
void BM_TrainPlaced4000NoBearings(benchmark::State& state) {
  train_placed(state, false);
}
// The same without trying the boards' centroid columns (harmoloc-train --no-columns): what
// their cross-validation costs.
void BM_TrainPlaced4000NoColumns(benchmark::State& state) {
  train_placed(state, true, false);
}
// The same measuring the area's gain by column (harmoloc-train --column-gain): what finding the
// pairs of frames over one place and the fit cost.
void BM_TrainPlaced4000ColumnGain(benchmark::State& state) {
  train_placed(state, true, true, true);
}

void BM_TrainMap204(benchmark::State& state) {
  train(state, 898, 64, 140, true);
}
void BM_TrainMap204AllBoards(benchmark::State& state) {
  train(state, 898, 64, 140, false);
}
void BM_TrainMap1024(benchmark::State& state) {
  train(state, 4000, 256, 768, true);
}

}  // namespace

BENCHMARK(BM_TrainPlaced4000)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrainPlaced4000NoBearings)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrainPlaced4000NoColumns)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrainPlaced4000ColumnGain)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_TrainMap204)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TrainMap204AllBoards)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TrainMap1024)->Unit(benchmark::kMillisecond)->Iterations(3);

BENCHMARK_MAIN();
