// The forward map the trainer fits (sim_host/forward_map_training.hpp): stored in tiles near the
// training run, so that a long route through a big room keeps fine cells.
#include "harmoloc/sim_host/forward_map_training.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/sim_host/coverage_plot.hpp"

namespace ha = harmoloc::algorithms;
namespace hs = harmoloc::sim_host;

namespace {

// A run along a diagonal of @p length_m from (0.5, 0.5), forth and back (two passes), a frame
// every 5 mm; two boards whose areas change smoothly along the way.
struct PlacedRun {
  std::vector<std::vector<float>> features;
  std::vector<hs::PlacedFrame> placed;
};

// Appends a frame at (x, y) facing @p yaw_rad with these two boards' features, @p travel_m
// along the run; its time follows from its index (30 Hz).
void add_frame(PlacedRun& run, double f0, double f1, double x, double y, double yaw_rad,
               double travel_m) {
  run.features.push_back({static_cast<float>(f0), static_cast<float>(f1)});
  hs::PlacedFrame f;
  f.index = run.features.size() - 1;
  f.t_s = static_cast<double>(f.index) / 30.0;
  f.travel_m = travel_m;
  f.pose = ha::Pose2{x, y, yaw_rad};
  run.placed.push_back(f);
}

PlacedRun diagonal_run(double length_m) {
  PlacedRun run;
  const double step = 0.005, heading = std::atan2(0.6, 0.8);
  const auto n = static_cast<std::size_t>(length_m / step);
  double travel = 0.0;
  for (std::size_t pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i <= n; ++i) {
      const double s = (pass == 0 ? static_cast<double>(i) : static_cast<double>(n - i)) * step;
      const double x = 0.5 + 0.8 * s, y = 0.5 + 0.6 * s;
      add_frame(run, 1.0 + 0.1 * s, 2.0 + std::sin(2.0 * s), x, y, heading, travel);
      travel += step;
    }
  }
  return run;
}

}  // namespace

TEST(ForwardMapTraining, ALongRouteKeepsFineCellsInTilesAlongIt) {
  const PlacedRun run = diagonal_run(12.0);  // a 9.6 x 7.2 m box: 2 cm cells would be 240,000 dense
  auto map = std::make_unique<ha::ForwardMap>();
  const hs::ForwardMapReport r =
      hs::train_forward_map_placed(run.features, run.placed, 2, hs::ForwardMapOptions{}, *map);
  EXPECT_LE(map->cell_m, 0.021F) << "cells of " << map->cell_m << " m";
  EXPECT_LE(map->tile_count, ha::ForwardMap::kMaxTiles);
  EXPECT_EQ(r.cells, map->stored_cells());
  EXPECT_LT(map->stored_cells(), map->columns * map->rows / 5) << "tiles only along the route";
  // Every place within the margin of the route reads stored cells, with what the run saw there.
  for (const double s : {0.0, 3.33, 7.77, 12.0}) {
    for (const double off : {-0.2, 0.0, 0.2}) {
      const double x = 0.5 + 0.8 * s - 0.6 * off, y = 0.5 + 0.6 * s + 0.8 * off;
      const ha::GridPoint p = ha::locate(*map, x, y);
      for (std::uint32_t i : p.index) EXPECT_NE(i, ha::ForwardMap::kVoidCell) << s << " " << off;
      EXPECT_NEAR(ha::route_distance(*map, p), std::fabs(off), 0.02) << s << " " << off;
      if (off == 0.0 && s > 0.0 && s < 12.0) {  // the ends see the kernel from one side
        std::array<float, ha::kMaxBoards> e{};
        ha::expected_features(*map, p, e.data());
        EXPECT_NEAR(e[0], 1.0 + 0.1 * s, 3e-3) << s;
        EXPECT_NEAR(e[1], 2.0 + std::sin(2.0 * s), 3e-3) << s;
        EXPECT_NEAR(ha::route_heading(*map, x, y), std::atan2(0.6, 0.8), 1e-6);
      }
    }
  }
  // Far from the route, in the box: no tile, the route term's distance.
  const ha::GridPoint far = ha::locate(*map, 0.5 + 9.6, 0.5);
  EXPECT_GE(ha::route_distance(*map, far), ha::ForwardMap::kVoidRouteDistance_m);
}

TEST(ForwardMapTraining, FewerTilesCoarsenTheCells) {
  const PlacedRun run = diagonal_run(6.0);
  auto fine = std::make_unique<ha::ForwardMap>();
  auto coarse = std::make_unique<ha::ForwardMap>();
  hs::train_forward_map_placed(run.features, run.placed, 2, hs::ForwardMapOptions{}, *fine);
  hs::ForwardMapOptions few;
  few.max_tiles = 64;  // the bare-metal kernels' capacity
  hs::train_forward_map_placed(run.features, run.placed, 2, few, *coarse);
  EXPECT_LE(coarse->tile_count, 64U);
  EXPECT_GT(fine->tile_count, 64U);
  EXPECT_GT(coarse->cell_m, 1.5F * fine->cell_m);
}

namespace {

// A straight pass along x at y = 0.5 (heading 0, or @p turn_rad for the second pass, which runs
// along y through the middle of the first), each frame's heading off by +-@p wobble_rad in turn.
PlacedRun crossing_run(double wobble_rad, double turn_rad) {
  PlacedRun run;
  const double step = 0.005;
  double travel = 0.0;
  for (std::size_t pass = 0; pass < 2; ++pass) {
    for (std::size_t i = 0; i <= 400; ++i) {
      const double s = static_cast<double>(i) * step;
      const double x = pass == 0 ? 0.5 + s : 1.5, y = pass == 0 ? 0.5 : s - 0.5;
      const double wobble = (i % 2 == 0 ? 1.0 : -1.0) * wobble_rad;
      add_frame(run, 1.0 + 0.1 * x, 2.0 + y, x, y, (pass == 0 ? 0.0 : turn_rad) + wobble, travel);
      travel += step;
    }
  }
  return run;
}

}  // namespace

// The heading stored per cell is the mean of the frames that run the way the nearest one does:
// one frame's wobble does not become the cell's heading, and where the route crosses itself
// the cell keeps one pass's heading instead of a mean of both.
TEST(ForwardMapTraining, CellHeadingIsTheMeanOfItsOwnPass) {
  const double deg = 3.14159265358979323846 / 180.0;
  const PlacedRun run = crossing_run(3.0 * deg, 90.0 * deg);
  auto map = std::make_unique<ha::ForwardMap>();
  hs::train_forward_map_placed(run.features, run.placed, 2, hs::ForwardMapOptions{}, *map);
  ASSERT_TRUE(map->has_heading);
  for (const double x : {0.8, 1.1, 2.2}) {  // along the first pass, away from the crossing
    for (const double off : {0.0, 0.003, 0.05}) {
      EXPECT_NEAR(ha::route_heading(*map, x, 0.5 + off), 0.0, 0.5 * deg) << x << " " << off;
    }
  }
  for (const double y : {-0.2, 0.2, 1.2}) {  // along the second
    EXPECT_NEAR(ha::route_heading(*map, 1.5, y), 90.0 * deg, 0.5 * deg) << y;
  }
  // At the crossing: one of the two, not 45 degrees.
  const double at = ha::route_heading(*map, 1.5, 0.5);
  EXPECT_LT(std::min(std::fabs(at), std::fabs(at - 90.0 * deg)), 3.5 * deg) << at / deg;
}

// Given the camera's offset ahead of the axle, a cell's bearings are kept over the camera's place
// and taken from every heading: a lane driven forth and back (the camera 15 cm ahead, so the two
// directions see the board from places 30 cm apart) is predicted at both headings, where the
// bearings over the axle's place fit one direction's view only.
TEST(ForwardMapTraining, BearingsOverTheCameraPlaceHoldAtEveryHeading) {
  const double deg = 3.14159265358979323846 / 180.0, d = 0.15;
  PlacedRun run;
  double travel = 0.0;
  for (int pass = 0; pass < 4; ++pass) {  // forth, back, forth, back along y = 0.5
    for (int i = 0; i <= 400; ++i) {
      const double s = 0.005 * (pass % 2 == 0 ? i : 400 - i);
      const double wobble = 0.01 * std::sin(1.3 * static_cast<double>(run.features.size()));
      add_frame(run, 1.0 + 0.1 * s + wobble, 2.0 + std::sin(2.0 * s), 0.5 + s, 0.5,
                pass % 2 == 0 ? 0.0 : 180.0 * deg, travel);
      travel += 0.005;
    }
  }
  const double bx = 1.5, by = 1.3;  // board 0, 0.8 m beside the lane's middle
  const auto truth = [&](double x, double y) { return std::atan2(by - y, bx - x); };
  hs::BearingObservations bearings;
  bearings.a1_rad = 1.2;
  bearings.world_rad.resize(run.features.size());
  for (const hs::PlacedFrame& f : run.placed) {
    const double noise = 0.1 * deg * std::sin(1.7 * static_cast<double>(f.index));
    const double cx = f.pose.x_m + d * std::cos(f.pose.yaw_rad);
    const double cy = f.pose.y_m + d * std::sin(f.pose.yaw_rad);
    bearings.world_rad[f.index] = {static_cast<float>(truth(cx, cy) + noise), std::nanf("")};
  }
  hs::ForwardMapOptions camera;
  camera.camera_forward_m = d;
  auto map = std::make_unique<ha::ForwardMap>();
  const hs::ForwardMapReport report =
      hs::train_forward_map_placed(run.features, run.placed, 2, camera, *map, &bearings);
  ASSERT_TRUE(map->has_bearings);
  EXPECT_FLOAT_EQ(map->bearing_camera_forward_m, static_cast<float>(d));
  EXPECT_DOUBLE_EQ(report.bearing_camera_forward_m, d);
  auto axle = std::make_unique<ha::ForwardMap>();
  hs::train_forward_map_placed(run.features, run.placed, 2, hs::ForwardMapOptions{}, *axle,
                               &bearings);
  ASSERT_TRUE(axle->has_bearings);
  EXPECT_EQ(axle->bearing_camera_forward_m, 0.0F);
  double axle_worst = 0.0;
  for (const double x : {0.9, 1.2, 1.5, 1.8, 2.1}) {
    for (const double yaw : {0.0, 180.0 * deg}) {
      const double c = std::cos(yaw), sn = std::sin(yaw);
      float b = 0.0F;
      ASSERT_TRUE(ha::expected_bearing(*map, ha::bearing_point(*map, x, 0.5, c, sn), 0, b))
          << x << " " << yaw;
      EXPECT_NEAR(b, truth(x + d * c, 0.5 + d * sn), 0.3 * deg) << x << " " << yaw / deg;
      ASSERT_TRUE(ha::expected_bearing(*axle, ha::bearing_point(*axle, x, 0.5, c, sn), 0, b));
      axle_worst =
          std::max(axle_worst, std::fabs(static_cast<double>(b) - truth(x + d * c, 0.5 + d * sn)));
    }
  }
  // Over the axle's place a cell holds one direction's bearing (or a mix): 30 cm along the lane
  // at 0.8 m is about 20 degrees.
  EXPECT_GT(axle_worst, 5.0 * deg);
}

// Bearings: each cell keeps the world bearing at which the training run saw a board from near
// it, and each board the spread of its bearing between passes; a board never seen whole gets
// none, and a stretch where a board was cut by the frame holds none.
TEST(ForwardMapTraining, CellBearingsAreWhereTheRunSawTheBoards) {
  const double deg = 3.14159265358979323846 / 180.0;
  PlacedRun run = diagonal_run(2.0);  // (0.5, 0.5) to (2.1, 1.7), forth and back
  hs::BearingObservations bearings;
  bearings.a1_rad = 1.2;
  bearings.a3_rad = 0.1;
  const double bx = 2.5, by = 0.0;  // board 0 stands here
  const auto truth = [&](double x, double y) { return std::atan2(by - y, bx - x); };
  bearings.world_rad.resize(run.features.size());
  for (const hs::PlacedFrame& f : run.placed) {
    // A deterministic +-0.2 degree wobble between frames, as a centroid's noise.
    const double noise = 0.2 * deg * std::sin(1.7 * static_cast<double>(f.index));
    const double s = std::hypot(f.pose.x_m - 0.5, f.pose.y_m - 0.5);
    const bool cut = s > 1.0 && s < 1.2;  // the board at the frame's edge along this stretch
    bearings.world_rad[f.index] = {
        cut ? std::nanf("") : static_cast<float>(truth(f.pose.x_m, f.pose.y_m) + noise),
        std::nanf("")};  // board 1 never gives a bearing
  }
  auto map = std::make_unique<ha::ForwardMap>();
  const hs::ForwardMapReport report = hs::train_forward_map_placed(
      run.features, run.placed, 2, hs::ForwardMapOptions{}, *map, &bearings);
  ASSERT_TRUE(map->has_bearings);
  ASSERT_TRUE(report.has_bearings);
  EXPECT_FLOAT_EQ(map->bearing_a1_rad, 1.2F);
  EXPECT_FLOAT_EQ(map->bearing_a3_rad, 0.1F);
  EXPECT_GT(map->bearing_sigma_rad[0], 0.09 * deg);
  EXPECT_LT(map->bearing_sigma_rad[0], 0.4 * deg);
  EXPECT_EQ(map->bearing_sigma_rad[1], 0.0F);
  EXPECT_GT(report.bearing_cells, 0U);
  for (const double s : {0.2, 0.6, 0.9, 1.5, 1.9}) {
    const double x = 0.5 + 0.8 * s, y = 0.5 + 0.6 * s;
    for (const double off : {0.0, 0.01}) {
      float b = 0.0F;
      ASSERT_TRUE(ha::expected_bearing(*map, ha::locate(*map, x - 0.6 * off, y + 0.8 * off), 0, b))
          << s;
      EXPECT_NEAR(b, truth(x - 0.6 * off, y + 0.8 * off), 0.3 * deg) << s << " " << off;
      EXPECT_FALSE(ha::expected_bearing(*map, ha::locate(*map, x, y), 1, b));
    }
  }
  float b = 0.0F;
  EXPECT_FALSE(ha::expected_bearing(*map, ha::locate(*map, 0.5 + 0.8 * 1.1, 0.5 + 0.6 * 1.1), 0, b))
      << "the cut stretch holds no bearing";

  // Without observations, or with every bearing missing, the map has none.
  auto plain = std::make_unique<ha::ForwardMap>();
  hs::train_forward_map_placed(run.features, run.placed, 2, hs::ForwardMapOptions{}, *plain);
  EXPECT_FALSE(plain->has_bearings);
  for (auto& v : bearings.world_rad) v = {std::nanf(""), std::nanf("")};
  hs::train_forward_map_placed(run.features, run.placed, 2, hs::ForwardMapOptions{}, *plain,
                               &bearings);
  EXPECT_FALSE(plain->has_bearings);
}

namespace {

// A floor driven in lanes: for each heading, 5 lanes 0.35 m apart across a 1.4 m square
// centred on (1.5, 1.5), each 1.4 m long, a frame every 5 mm; the robot travels 1 m between
// lanes, so that each lane is a pass of its own. The second board's feature changes with the
// heading by @p heading_gain sin(heading) (a board nearer the frame's edge at one heading).
PlacedRun lanes_run(const std::vector<double>& headings_rad, double heading_gain = 0.0) {
  PlacedRun run;
  const double step = 0.005;
  double travel = 0.0;
  for (const double h : headings_rad) {
    const double ux = std::cos(h), uy = std::sin(h);
    for (int lane = -2; lane <= 2; ++lane) {
      const double off = 0.35 * lane;
      for (int i = 0; i <= 280; ++i) {
        const double s = -0.7 + step * i;
        const double x = 1.5 + s * ux - off * uy, y = 1.5 + s * uy + off * ux;
        add_frame(run, 1.0 + 0.1 * x, 2.0 + y + heading_gain * std::sin(h), x, y, h, travel);
        travel += step;
      }
      travel += 1.0;
    }
  }
  return run;
}

}  // namespace

// How far apart in heading the passes over one place run (the upper quartile): a route's passes
// (forth and back, reversing) within a degree, a floor's lanes at two headings 30 degrees apart
// by that; lanes at one heading are a route too. The firmware tells floor maps by it.
TEST(ForwardMapTraining, PassHeadingSpreadTellsAFloorFromARoute) {
  const double deg = 3.14159265358979323846 / 180.0;
  const auto spread = [](const PlacedRun& run) {
    auto map = std::make_unique<ha::ForwardMap>();
    return hs::train_forward_map_placed(run.features, run.placed, 2, hs::ForwardMapOptions{}, *map)
        .pass_heading_spread_rad;
  };
  EXPECT_LT(spread(diagonal_run(3.0)), 1.0 * deg);
  EXPECT_LT(spread(lanes_run({0.4})), 1.0 * deg);
  const double floor = spread(lanes_run({0.4, 0.4 + 30.0 * deg}));
  EXPECT_NEAR(floor, 30.0 * deg, 1.0 * deg) << floor / deg;
  EXPECT_GE(floor, static_cast<double>(ha::kFloorMapPassHeadingSpread_rad));
}

// Where the boards' areas change with the heading, a floor's map models them over the heading
// (the first harmonic), and predicts each lane's view where the lanes cross; lanes at one heading
// (a route) get no heading terms.
TEST(ForwardMapTraining, HeadingTermsWhereTheAreasChangeWithTheHeading) {
  const double deg = 3.14159265358979323846 / 180.0;
  const double h0 = 0.4, h1 = 0.4 + 30.0 * deg;
  auto map = std::make_unique<ha::ForwardMap>();
  const PlacedRun floor = lanes_run({h0, h1}, 0.8);
  hs::ForwardMapOptions with;
  with.heading_ridges = hs::kHeadingRidges;
  const hs::ForwardMapReport r =
      hs::train_forward_map_placed(floor.features, floor.placed, 2, with, *map);
  ASSERT_TRUE(map->has_heading_terms);
  EXPECT_GT(r.heading_ridge, 0.0);
  EXPECT_LT(r.validation_rmse, 0.3 * r.mean_validation_rmse)
      << r.validation_rmse << " " << r.mean_validation_rmse;
  std::array<float, ha::kMaxBoards> e{};
  for (const double h : {h0, h1}) {
    ha::expected_features(*map, ha::locate(*map, 1.5, 1.5), ha::seen_heading(h), e.data());
    EXPECT_NEAR(e[1], 2.0 + 1.5 + 0.8 * std::sin(h), 0.03) << h;
    EXPECT_NEAR(e[0], 1.0 + 0.15, 0.01) << h;
  }
  // The headings the lanes were driven at (and 30 degrees around them: 45 from a sector's
  // centre) are covered where they cross; the opposite ones are not.
  ASSERT_TRUE(map->has_heading_coverage);
  const ha::GridPoint centre = ha::locate(*map, 1.5, 1.5);
  for (const double h : {h0, h1, h0 - 30.0 * deg, h1 + 30.0 * deg})
    EXPECT_TRUE(ha::heading_covered(*map, centre, ha::seen_heading(h))) << h / deg;
  for (const double h : {h0 + 180.0 * deg, h0 - 90.0 * deg, h1 + 90.0 * deg})
    EXPECT_FALSE(ha::heading_covered(*map, centre, ha::seen_heading(h))) << h / deg;
  // Two lanes 30 degrees apart, each reaching 45 degrees: 120 of 360 degrees.
  EXPECT_GT(r.covered_heading_fraction, 0.25);
  EXPECT_LT(r.covered_heading_fraction, 0.45);
  auto plain = std::make_unique<ha::ForwardMap>();
  const PlacedRun route = lanes_run({h0}, 0.8);
  hs::train_forward_map_placed(route.features, route.placed, 2, with, *plain);
  EXPECT_FALSE(plain->has_heading_terms);
  // Without ridges to try (the default), none either.
  hs::train_forward_map_placed(floor.features, floor.placed, 2, hs::ForwardMapOptions{}, *plain);
  EXPECT_FALSE(plain->has_heading_terms);
}

// A floor driven forth and back in lanes 0.35 m apart (a boustrophedon): each place was driven
// at one heading, the lane through it; the opposite heading only on the neighbouring lanes. The
// heading terms are then fitted over a wide kernel with the areas' change across the lanes taken
// out (forward_map_training_fit.cpp, wide_fit), and a lane's place is predicted at both headings.
TEST(ForwardMapTraining, HeadingTermsReachTheNeighbouringLanesOfAForthAndBackFloor) {
  const double pi = 3.14159265358979323846;
  PlacedRun run;
  const double step = 0.005;
  double travel = 0.0;
  for (int lane = -2; lane <= 2; ++lane) {
    const double y = 1.5 + 0.35 * lane;
    const double h = lane % 2 == 0 ? 0.0 : pi;
    for (int i = 0; i <= 280; ++i) {
      const double s = -0.7 + step * i;
      const double x = 1.5 + (lane % 2 == 0 ? s : -s);
      add_frame(run, 1.0 + 0.1 * x, 2.0 + y + 0.8 * std::cos(h), x, y, h, travel);
      travel += step;
    }
    travel += 1.0;
  }
  hs::ForwardMapOptions with;
  with.heading_ridges = hs::kHeadingRidges;
  auto map = std::make_unique<ha::ForwardMap>();
  const hs::ForwardMapReport r =
      hs::train_forward_map_placed(run.features, run.placed, 2, with, *map);
  ASSERT_TRUE(map->has_heading_terms);
  EXPECT_GT(r.heading_bandwidth_m, 0.0);
  EXPECT_LT(r.validation_rmse, 0.2 * r.mean_validation_rmse)
      << r.validation_rmse << " " << r.mean_validation_rmse;
  std::array<float, ha::kMaxBoards> e{};
  for (const double y : {1.5, 1.85}) {
    for (const double h : {0.0, pi}) {
      ha::SeenHeading seen = ha::seen_heading(h);
      seen.keep_to_coverage = false;
      ha::expected_features(*map, ha::locate(*map, 1.5, y), seen, e.data());
      EXPECT_NEAR(e[1], 2.0 + y + 0.8 * std::cos(h), 0.05) << y << " " << h;
      EXPECT_NEAR(e[0], 1.15, 0.02) << y << " " << h;
    }
  }
  // Fitted over the narrow kernel alone (no wide kernel to try), the other heading is read from
  // the lane's own: off by the heading's whole share.
  with.heading_bandwidths_m.clear();
  auto narrow = std::make_unique<ha::ForwardMap>();
  hs::train_forward_map_placed(run.features, run.placed, 2, with, *narrow);
  ha::SeenHeading back = ha::seen_heading(pi);
  back.keep_to_coverage = false;
  ha::expected_features(*narrow, ha::locate(*narrow, 1.5, 1.5), back, e.data());
  EXPECT_GT(std::fabs(static_cast<double>(e[1]) - (2.0 + 1.5 - 0.8)), 0.4) << e[1];
}

// The coverage picture: the places within the known distance only, a wedge for each covered
// sector, pointing the way the camera faced (map y up is page y down).
TEST(CoveragePlot, WedgesForCoveredHeadingsAtKnownPlaces) {
  auto map = std::make_unique<ha::ForwardMap>();
  ASSERT_TRUE(ha::lay_out_grid(*map, 16, 16));
  map->cell_m = 0.05F;
  map->board_count = 1;
  map->has_heading = true;
  map->has_heading_coverage = true;
  for (std::uint32_t r = 0; r < 16; ++r) {
    for (std::uint32_t c = 0; c < 16; ++c) {
      const std::size_t at = map->index(c, r);
      map->route_distance_m[at] = c < 8 ? 0.0F : 1.0F;
      map->heading_cover[at] = 1U << 8;  // 0 to 22.5 degrees
    }
  }
  const std::string svg = hs::coverage_svg(*map, 0.1, "test");
  const auto count = [&svg](const std::string& pattern) {
    const std::regex re(pattern);
    return std::distance(std::sregex_iterator(svg.begin(), svg.end(), re), std::sregex_iterator());
  };
  const auto places = count("h[0-9.]+v[0-9.]+h-[0-9.]+z");
  const auto wedges = count(" 0 0 0 ");
  EXPECT_GT(places, 20);
  EXPECT_LT(places, 150);  // about half of 16 x 16 blocks of one cell
  EXPECT_EQ(wedges, places);
  std::smatch m;
  const std::regex wedge(
      "M([0-9.]+) ([0-9.]+)L([0-9.]+) ([0-9.]+)A[0-9.]+ [0-9.]+ 0 0 0 ([0-9.]+) ([0-9.]+)z");
  ASSERT_TRUE(std::regex_search(svg, m, wedge));
  const double cx = std::stod(m[1]), cy = std::stod(m[2]);
  EXPECT_GT(std::stod(m[3]), cx + 1.0);  // 0 degrees: to the right
  EXPECT_NEAR(std::stod(m[4]), cy, 0.11);
  EXPECT_GT(std::stod(m[5]), cx + 1.0);  // 22.5 degrees: right and up the page
  EXPECT_LT(std::stod(m[6]), cy - 1.0);
  // Known nowhere: no place and no wedge.
  const std::string none = hs::coverage_svg(*map, -1.0, "test");
  EXPECT_EQ(none.find(" 0 0 0 "), std::string::npos);
}

// Visibility: a lane driven forth and back with a board ahead at one end. Driving towards it the
// camera sees it whole, driving away not at all; the map's features over every heading mix the
// two, visibility keeps the board's whole feature at the camera's place and predicts both
// directions, and a heading never driven (across the lane) as out of view. Its noise is the
// spread of those predictions, far narrower than the mix's.
TEST(ForwardMapTraining, VisibilityPredictsABoardInViewAndOutOfView) {
  const double deg = 3.14159265358979323846 / 180.0, d = 0.15;
  const double bx = 3.2, by = 0.7;  // board 0, ahead of the lane's +x end
  const auto whole = [&](double cx, double cy) {
    return 0.3 / ((bx - cx) * (bx - cx) + (by - cy) * (by - cy));
  };
  // The lane driven both ways (four passes: a floor map), or only towards the board (passes
  // 0 and 2: a route map).
  const auto drive = [&](PlacedRun& run, hs::BearingObservations& bearings, int step) {
    bearings.a1_rad = 1.2;  // half field of view 0.6 rad
    double travel = 0.0;
    for (int pass = 0; pass < 4; pass += step) {
      for (int i = 0; i <= 400; ++i) {
        const double x = 0.5 + 0.005 * (pass % 2 == 0 ? i : 400 - i);
        const double yaw = pass % 2 == 0 ? 0.0 : 180.0 * deg;
        const double cx = x + d * std::cos(yaw), cy = 0.5 + d * std::sin(yaw);
        const double wobble = 1.0 + 0.01 * std::sin(1.3 * static_cast<double>(run.features.size()));
        const bool in_view = pass % 2 == 0;
        add_frame(run, in_view ? whole(cx, cy) * wobble : 0.0, 2.0 + std::sin(2.0 * x), x, 0.5, yaw,
                  travel);
        travel += 0.005;
        bearings.world_rad.push_back(
            {in_view ? static_cast<float>(std::atan2(by - cy, bx - cx)) : std::nanf(""),
             std::nanf("")});
        bearings.half_width_rad.push_back({in_view ? 0.02F : 0.0F, 0.0F});
      }
    }
    // Where the boards stand, as the bearings' calibration places them: board 0 only.
    bearings.placements.resize(2);
    bearings.placements[0].placed = true;
    bearings.placements[0].x_m = bx;
    bearings.placements[0].y_m = by;
  };
  const auto train = [](const PlacedRun& r, const hs::BearingObservations& b,
                        const hs::ForwardMapOptions& o, ha::ForwardMap& m) {
    return hs::train_forward_map_placed(r.features, r.placed, 2, o, m, &b);
  };
  PlacedRun run;
  hs::BearingObservations bearings;
  drive(run, bearings, 1);
  hs::ForwardMapOptions opt;
  opt.camera_forward_m = d;
  auto map = std::make_unique<ha::ForwardMap>();
  const hs::ForwardMapReport report = train(run, bearings, opt, *map);
  ASSERT_TRUE(map->has_visibility);
  ASSERT_TRUE(report.visibility);
  EXPECT_TRUE(report.visibility_wanted);
  // Lanes at opposite headings make a floor map: visibility by default; without it, the mix.
  auto mixed = std::make_unique<ha::ForwardMap>();
  opt.visibility_on_floors = false;
  const hs::ForwardMapReport mixed_report = train(run, bearings, opt, *mixed);
  ASSERT_FALSE(mixed->has_visibility);
  EXPECT_FALSE(mixed_report.visibility_wanted);
  double mixed_worst = 0.0;
  for (const double x : {1.0, 1.5, 2.0}) {
    const double in_view = whole(x + d, 0.5);
    const auto at = [&](const ha::ForwardMap& m, double yaw) {
      std::array<float, ha::kMaxBoards> e{};
      ha::expected_at_pose(m, ha::locate(m, x, 0.5), x, 0.5, ha::seen_heading(yaw), e.data());
      return static_cast<double>(e[0]);
    };
    EXPECT_NEAR(at(*map, 0.0), in_view, 0.03 * in_view) << x;
    EXPECT_LT(at(*map, 180.0 * deg), 0.01 * in_view) << x;
    EXPECT_LT(at(*map, 90.0 * deg), 0.01 * in_view) << x;  // never driven: out of view
    // Turned 10 degrees from the lane the board is still whole in view; the camera stands 2.6
    // cm off the lane, and the lane's views are carried there by where the board stands.
    const double turned = whole(x + d * std::cos(10.0 * deg), 0.5 - d * std::sin(10.0 * deg));
    EXPECT_NEAR(at(*map, -10.0 * deg), turned, 0.03 * turned) << x;
    mixed_worst = std::max({mixed_worst, std::fabs(at(*mixed, 0.0) - in_view) / in_view,
                            at(*mixed, 180.0 * deg) / in_view});
  }
  EXPECT_GT(mixed_worst, 0.3);
  // The feature does not change across the frame here: no angle gain to speak of.
  EXPECT_NEAR(report.visibility_angle_gain, 0.0, 0.1);
  EXPECT_LT(report.sigma[0], 0.25 * mixed_report.sigma[0]);
  // Board 1 gives no bearing: it keeps the mixed map's noise and features.
  EXPECT_DOUBLE_EQ(report.sigma[1], mixed_report.sigma[1]);
  // A route map holds visibility only when asked for.
  PlacedRun route;
  hs::BearingObservations route_bearings;
  drive(route, route_bearings, 2);
  hs::ForwardMapOptions route_opt;
  route_opt.camera_forward_m = d;
  auto route_map = std::make_unique<ha::ForwardMap>();
  const hs::ForwardMapReport route_report = train(route, route_bearings, route_opt, *route_map);
  EXPECT_FALSE(route_report.visibility);
  EXPECT_FALSE(route_report.visibility_wanted);
  EXPECT_FALSE(route_map->has_visibility);
  EXPECT_TRUE(route_map->has_bearings);
  route_opt.visibility = true;
  EXPECT_TRUE(train(route, route_bearings, route_opt, *route_map).visibility);
  EXPECT_TRUE(route_map->has_visibility);
}
