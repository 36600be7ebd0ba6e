// A board's geometry fitted to its sightings (board_geometry_fit.hpp): exact sightings from the
// projection, sightings partly hidden, too few sightings, and the firmware segmentation of
// rendered random scenes seen from a grid of poses and headings over their floors.
#include "harmoloc/sim_host/board_geometry_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/board_projection.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"

namespace hs = harmoloc::sim_host;
namespace ha = harmoloc::algorithms;

namespace {

constexpr double kPi = 3.14159265358979323846;

double angle_error_deg(double a, double b) {
  return std::fabs(std::remainder(a - b, 2.0 * kPi)) * 180.0 / kPi;
}

// Poses on a grid over the floor plan, at every covered heading and 0.3 rad either side.
std::vector<ha::Pose2> grid_poses(const hs::FloorPlan& plan, int along_n, int across_n) {
  std::vector<ha::Pose2> poses;
  const double ca = std::cos(plan.axis_rad), sa = std::sin(plan.axis_rad);
  for (int i = 0; i < along_n; ++i) {
    for (int j = 0; j < across_n; ++j) {
      const double along = plan.half_length_m * (-1.0 + 2.0 * i / (along_n - 1));
      const double across = plan.half_width_m * (-1.0 + 2.0 * j / (across_n - 1));
      for (double h : plan.headings_rad) {
        for (double d : {-0.3, 0.0, 0.3}) {
          poses.push_back({plan.centre_x_m + along * ca - across * sa,
                           plan.centre_y_m + along * sa + across * ca, h + d});
        }
      }
    }
  }
  return poses;
}

std::vector<hs::BoardSighting> projected_sightings(const hs::CameraSpec& camera,
                                                   const hs::LensModel& lens,
                                                   const hs::BoardSpec& board,
                                                   const std::vector<ha::Pose2>& poses) {
  std::vector<hs::BoardSighting> out;
  for (const ha::Pose2& p : poses) {
    const hs::BoardImage im = hs::project_board(camera, lens, board, p);
    out.push_back({p, im.area_px, im.centroid_u_px, im.centroid_v_px});
  }
  return out;
}

// A board of the random scene that the grid sees well: the one seen from most poses.
std::size_t best_seen_board(const hs::Scenario& s, const hs::LensModel& lens,
                            const std::vector<ha::Pose2>& poses) {
  std::size_t best = 0, best_n = 0;
  for (std::size_t b = 0; b < s.boards.size(); ++b) {
    std::size_t n = 0;
    for (const ha::Pose2& p : poses)
      n += hs::project_board(s.camera, lens, s.boards[b], p).area_px > 100.0;
    if (n > best_n) {
      best_n = n;
      best = b;
    }
  }
  return best;
}

TEST(BoardGeometryFit, RecoversABoardFromItsProjectedSightings) {
  for (std::uint64_t seed : {4U, 7U}) {
    const hs::Scenario s = hs::random_scenario(seed);
    const hs::LensModel lens(s.camera);
    const std::vector<ha::Pose2> poses = grid_poses(hs::floor_plan(s), 4, 3);
    const hs::BoardSpec truth = s.boards[best_seen_board(s, lens, poses)];
    const std::vector<hs::BoardSighting> seen = projected_sightings(s.camera, lens, truth, poses);
    // Placed 25 cm off, as a triangulation from columns may be.
    const hs::BoardSpec start = hs::start_board_geometry(
        s.camera, lens, seen, truth.centre_x_m + 0.2, truth.centre_y_m - 0.15, truth);
    const hs::BoardFit fit = hs::fit_board_geometry(s.camera, lens, seen, start);
    ASSERT_TRUE(fit.ok) << "seed " << seed << ", " << fit.sightings_used << " sightings";
    EXPECT_NEAR(fit.board.centre_x_m, truth.centre_x_m, 0.01) << seed;
    EXPECT_NEAR(fit.board.centre_y_m, truth.centre_y_m, 0.01) << seed;
    EXPECT_NEAR(fit.board.centre_z_m, truth.centre_z_m, 0.01) << seed;
    EXPECT_NEAR(fit.board.width_m / truth.width_m, 1.0, 0.01) << seed;
    EXPECT_NEAR(fit.board.height_m / truth.height_m, 1.0, 0.01) << seed;
    EXPECT_LT(angle_error_deg(fit.board.facing_yaw_rad, truth.facing_yaw_rad), 0.5) << seed;
    EXPECT_LT(fit.rms_column_px, 0.05) << seed;
  }
}

TEST(BoardGeometryFit, HiddenSightingsDoNotPullTheFit) {
  const hs::Scenario s = hs::random_scenario(4);
  const hs::LensModel lens(s.camera);
  const std::vector<ha::Pose2> poses = grid_poses(hs::floor_plan(s), 4, 3);
  const hs::BoardSpec truth = s.boards[best_seen_board(s, lens, poses)];
  std::vector<hs::BoardSighting> seen = projected_sightings(s.camera, lens, truth, poses);
  // Every fifth sighting has its left half hidden (a person): half the area, centroid moved.
  std::size_t hidden = 0;
  for (std::size_t i = 0; i < seen.size(); i += 5) {
    if (seen[i].area_px <= 0.0) continue;
    seen[i].area_px *= 0.5;
    seen[i].centroid_u_px += 0.25 * std::sqrt(seen[i].area_px * 2.0);
    ++hidden;
  }
  ASSERT_GE(hidden, 10U);
  const hs::BoardSpec start = hs::start_board_geometry(s.camera, lens, seen, truth.centre_x_m - 0.2,
                                                       truth.centre_y_m + 0.2, truth);
  const hs::BoardFit fit = hs::fit_board_geometry(s.camera, lens, seen, start);
  ASSERT_TRUE(fit.ok);
  EXPECT_NEAR(fit.board.centre_x_m, truth.centre_x_m, 0.03);
  EXPECT_NEAR(fit.board.centre_y_m, truth.centre_y_m, 0.03);
  EXPECT_NEAR(fit.board.centre_z_m, truth.centre_z_m, 0.03);
  EXPECT_NEAR(fit.board.width_m / truth.width_m, 1.0, 0.05);
  EXPECT_GT(fit.outlier_share, 0.05);  // the hidden ones are found out, not fitted
}

TEST(BoardGeometryFit, TooFewSightingsIsNotOk) {
  const hs::Scenario s = hs::random_scenario(4);
  const hs::LensModel lens(s.camera);
  std::vector<ha::Pose2> poses = grid_poses(hs::floor_plan(s), 4, 3);
  poses.resize(5);
  const hs::BoardSpec truth = s.boards[0];
  const std::vector<hs::BoardSighting> seen = projected_sightings(s.camera, lens, truth, poses);
  const hs::BoardFit fit = hs::fit_board_geometry(s.camera, lens, seen, truth);
  EXPECT_FALSE(fit.ok);
  EXPECT_LE(fit.sightings_used, 5U);
}

// The real path: frames rendered with noise, vignetting and the scene's light, segmented by the
// firmware, each board's pixels and centroid column and row as sightings. Boards hidden behind
// others, stands, lens edges and the frame's border are all in there.
TEST(BoardGeometryFit, FitsTheSegmentedFramesOfRandomScenes) {
  std::vector<double> centre_cm, size_pct, facing_deg;
  std::size_t boards = 0, fitted = 0;
  for (std::uint64_t seed : {3U, 5U}) {
    const hs::Scenario s = hs::random_scenario(seed);
    const hs::LensModel lens(s.camera);
    const std::vector<ha::Pose2> poses = grid_poses(hs::floor_plan(s), 4, 3);
    hs::SceneRenderer renderer(s);
    const ha::ThresholdSet windows = hs::threshold_set(hs::thresholds_for(s));
    std::vector<std::vector<hs::BoardSighting>> seen(s.boards.size());
    std::vector<std::uint8_t> rgb;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      renderer.render(poses[i], seed * 1000U + i, rgb);
      ha::AreaVector a;
      ha::segment_rgb24(rgb.data(), s.camera.width_px, s.camera.height_px, s.camera.width_px * 3U,
                        windows, a);
      for (std::size_t b = 0; b < s.boards.size(); ++b) {
        seen[b].push_back({poses[i], static_cast<double>(a.pixels[b]), a.centroid_column_px(b),
                           a.centroid_row_px(b)});
      }
    }
    for (std::size_t b = 0; b < s.boards.size(); ++b) {
      const hs::BoardSpec& truth = s.boards[b];
      const hs::BoardSpec start = hs::start_board_geometry(
          s.camera, lens, seen[b], truth.centre_x_m + 0.15, truth.centre_y_m + 0.15, truth);
      const hs::BoardFit fit = hs::fit_board_geometry(s.camera, lens, seen[b], start);
      ++boards;
      // A board the floor sees from enough places is fitted; seed 3's floor sees two boards
      // from 2 and 0 places.
      if (fit.sightings_used >= 30) EXPECT_TRUE(fit.ok) << "seed " << seed << " board " << b;
      if (!fit.ok) continue;
      ++fitted;
      centre_cm.push_back(100.0 * std::sqrt(std::pow(fit.board.centre_x_m - truth.centre_x_m, 2) +
                                            std::pow(fit.board.centre_y_m - truth.centre_y_m, 2) +
                                            std::pow(fit.board.centre_z_m - truth.centre_z_m, 2)));
      size_pct.push_back(100.0 * std::fabs(std::sqrt(fit.board.width_m * fit.board.height_m /
                                                     (truth.width_m * truth.height_m)) -
                                           1.0));
      facing_deg.push_back(angle_error_deg(fit.board.facing_yaw_rad, truth.facing_yaw_rad));
    }
  }
  ASSERT_GE(fitted, 6U);
  for (auto* v : {&centre_cm, &size_pct, &facing_deg}) std::sort(v->begin(), v->end());
  const std::size_t n = centre_cm.size();
  std::printf(
      "%zu of %zu boards fitted; centre error median %.2f worst %.2f cm, size %.2f / "
      "%.2f %%, facing %.2f / %.2f deg\n",
      fitted, boards, centre_cm[n / 2], centre_cm[n - 1], size_pct[n / 2], size_pct[n - 1],
      facing_deg[n / 2], facing_deg[n - 1]);
  // When written: 11 of 13 boards, centre 0.22 / 2.14 cm, size 0.20 / 2.34 %, facing 0.51 /
  // 11.0 degrees (the worst: a board seen only nearly face on, whose width and facing trade).
  EXPECT_LT(centre_cm[n / 2], 1.0);
  EXPECT_LT(centre_cm[n - 1], 5.0);
  EXPECT_LT(size_pct[n / 2], 1.0);
  EXPECT_LT(size_pct[n - 1], 5.0);
  EXPECT_LT(facing_deg[n / 2], 2.0);
  EXPECT_LT(facing_deg[n - 1], 15.0);
}

}  // namespace
