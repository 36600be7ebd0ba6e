// The boards' images from geometry alone (board_projection.hpp): closed forms on a pinhole, the
// frame's border, a barrel lens's fold-back, and the renderer's own pixel counts and the firmware
// segmentation's centroids on random scenes.
#include "harmoloc/sim_host/board_projection.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/scene_renderer.hpp"

namespace hs = harmoloc::sim_host;
namespace ha = harmoloc::algorithms;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A pinhole at 0.5 m, level, no offset from the axle: the robot at the origin looks along +x.
hs::CameraSpec pinhole() {
  hs::CameraSpec c;
  c.width_px = 320;
  c.height_px = 240;
  c.horizontal_fov_deg = 70.0;
  c.k1 = c.k2 = c.k3 = c.p1 = c.p2 = 0.0;
  c.principal_offset_x_px = c.principal_offset_y_px = 0.0;
  c.height_m = 0.5;
  c.pitch_deg = 0.0;
  c.mount_yaw_deg = 0.0;
  c.forward_offset_m = 0.0;
  return c;
}

// A 0.5 x 0.4 m board at the camera's height @p distance_m ahead, its face turned back towards
// the camera by @p turn_rad.
hs::BoardSpec board_ahead(double distance_m, double turn_rad = 0.0) {
  hs::BoardSpec b;
  b.name = "test";
  b.centre_x_m = distance_m;
  b.centre_y_m = 0.0;
  b.centre_z_m = 0.5;
  b.width_m = 0.5;
  b.height_m = 0.4;
  b.facing_yaw_rad = kPi + turn_rad;
  return b;
}

// Pose @p i of 12 spread over the floor plan, at a covered heading give or take 0.1 rad.
ha::Pose2 floor_pose(const hs::FloorPlan& plan, int i) {
  const double ca = std::cos(plan.axis_rad), sa = std::sin(plan.axis_rad);
  const double along = plan.half_length_m * (-1.0 + 2.0 * ((i * 7) % 12) / 11.0);
  const double across = plan.half_width_m * (-1.0 + 2.0 * ((i * 5) % 12) / 11.0);
  return {plan.centre_x_m + along * ca - across * sa, plan.centre_y_m + along * sa + across * ca,
          plan.headings_rad[static_cast<std::size_t>(i) % plan.headings_rad.size()] +
              0.1 * ((i % 3) - 1)};
}

double focal_px(const hs::CameraSpec& c) {
  return 0.5 * c.width_px / std::tan(0.5 * c.horizontal_fov_deg * kPi / 180.0);
}

TEST(BoardProjection, FacingTheCameraIsFocalSquaredTimesAreaOverDistanceSquared) {
  const hs::CameraSpec c = pinhole();
  const hs::LensModel lens(c);
  const hs::BoardImage im = hs::project_board(c, lens, board_ahead(3.0), ha::Pose2{0, 0, 0});
  const double f = focal_px(c);
  EXPECT_NEAR(im.area_px, f * f * 0.5 * 0.4 / 9.0, 1e-6 * im.area_px);
  EXPECT_NEAR(im.centroid_u_px, 0.5 * c.width_px - 0.5, 1e-6);
  EXPECT_NEAR(im.centroid_v_px, 0.5 * c.height_px - 0.5, 1e-6);
  EXPECT_FALSE(im.cut);
  hs::BoardSpec ellipse = board_ahead(3.0);
  ellipse.shape = hs::BoardShape::kEllipse;
  const hs::BoardImage e = hs::project_board(c, lens, ellipse, ha::Pose2{0, 0, 0});
  EXPECT_NEAR(e.area_px / im.area_px, kPi / 4.0, 0.005);  // a 48-gon inscribed in the ellipse
}

TEST(BoardProjection, ATurnedBoardShrinksByTheCosine) {
  const hs::CameraSpec c = pinhole();
  const hs::LensModel lens(c);
  const double flat = hs::project_board(c, lens, board_ahead(4.0), ha::Pose2{0, 0, 0}).area_px;
  const double turned =
      hs::project_board(c, lens, board_ahead(4.0, kPi / 3.0), ha::Pose2{0, 0, 0}).area_px;
  EXPECT_NEAR(turned / flat, 0.5, 0.01);  // perspective adds a little at 4 m
}

TEST(BoardProjection, TheFramesBorderCutsTheBoard) {
  const hs::CameraSpec c = pinhole();
  const hs::LensModel lens(c);
  const double whole = hs::project_board(c, lens, board_ahead(3.0), ha::Pose2{0, 0, 0}).area_px;
  // The robot turned so the board's centre lies on the frame's left border (the half field of
  // view), the board turned with it: parallel to the image plane, its image is a scaled copy (by
  // the depth, 3 cos(half_fov) m), of which the border keeps half.
  const double half_fov = 0.5 * c.horizontal_fov_deg * kPi / 180.0;
  const hs::BoardImage im =
      hs::project_board(c, lens, board_ahead(3.0, -half_fov), ha::Pose2{0, 0, -half_fov});
  EXPECT_TRUE(im.cut);
  const double depth_scale = 1.0 / (std::cos(half_fov) * std::cos(half_fov));
  EXPECT_NEAR(im.area_px / (whole * depth_scale), 0.5, 1e-6);
  EXPECT_LT(im.centroid_u_px, 0.25 * c.width_px);
}

TEST(BoardProjection, ABoardBehindTheCameraShowsNothing) {
  const hs::CameraSpec c = pinhole();
  const hs::LensModel lens(c);
  const hs::BoardImage im = hs::project_board(c, lens, board_ahead(-3.0, kPi), ha::Pose2{0, 0, 0});
  EXPECT_EQ(im.area_px, 0.0);
  const hs::BoardImage side =
      hs::project_board(c, lens, board_ahead(3.0), ha::Pose2{0, 0, kPi / 2});
  EXPECT_EQ(side.area_px, 0.0);
}

// Beyond a barrel lens's monotonic radius the distortion polynomial turns back: a board far
// outside the view would land inside the frame if its points were distorted there.
TEST(BoardProjection, ABarrelLensDoesNotFoldAFarBoardIntoTheFrame) {
  hs::CameraSpec c = pinhole();
  c.k1 = -0.25;
  const hs::LensModel lens(c);
  for (double deg : {60.0, 70.0, 80.0}) {
    const double a = deg * kPi / 180.0;
    const hs::BoardImage im = hs::project_board(c, lens, board_ahead(3.0, -a), ha::Pose2{0, 0, -a});
    EXPECT_EQ(im.area_px, 0.0) << deg << " degrees off the axis";
  }
  const double a = 20.0 * kPi / 180.0;
  const hs::BoardImage near = hs::project_board(c, lens, board_ahead(3.0, -a), ha::Pose2{0, 0, -a});
  EXPECT_GT(near.area_px, 100.0);
  EXPECT_FALSE(near.cut);
}

// The renderer counts the pixels whose rays meet each board; the projection should give the same
// area wherever nothing hides the board: on random scenes (lenses, pitches, tilted boards,
// ellipses, stands) at poses over their floors, at the headings the floor is driven at.
TEST(BoardProjection, AgreesWithTheRenderersPixelCounts) {
  std::vector<double> rel;
  int compared = 0;
  for (std::uint64_t seed : {3U, 5U, 9U}) {
    const hs::Scenario s = hs::random_scenario(seed);
    const hs::FloorPlan plan = hs::floor_plan(s);
    hs::SceneRenderer renderer(s);
    const hs::LensModel lens(s.camera);
    for (int i = 0; i < 12; ++i) {
      const ha::Pose2 pose = floor_pose(plan, i);
      const std::vector<std::uint32_t> seen = renderer.visible_board_pixels(pose);
      for (std::size_t b = 0; b < s.boards.size(); ++b) {
        const hs::BoardImage im = hs::project_board(s.camera, lens, s.boards[b], pose);
        if (im.area_px < 100.0) continue;
        ++compared;
        rel.push_back(std::fabs(seen[b] / im.area_px - 1.0));
      }
    }
  }
  ASSERT_GE(compared, 60);
  std::sort(rel.begin(), rel.end());
  const double median = rel[rel.size() / 2];
  const double p80 = rel[rel.size() * 8 / 10];
  EXPECT_LT(median, 0.01) << "of " << compared;
  // 0.3% and 1.0% when written (144 images); the tail: boards partly hidden by another board or
  // a stand, which the projection ignores.
  EXPECT_LT(p80, 0.03) << "of " << compared;
}

// The firmware's segmentation of rendered frames (noise, vignetting, the scene's light) puts each
// board's centroid column and row where the projection puts the centroid: what the trainer's fit
// of the boards' geometry compares. Boards partly hidden (the renderer's count off the
// projection's) are left out.
TEST(BoardProjection, SegmentedCentroidsAreTheProjectedCentroids) {
  std::vector<double> du, dv;
  for (std::uint64_t seed : {3U, 5U, 9U}) {
    const hs::Scenario s = hs::random_scenario(seed);
    const hs::FloorPlan plan = hs::floor_plan(s);
    hs::SceneRenderer renderer(s);
    const hs::LensModel lens(s.camera);
    const ha::ThresholdSet windows = hs::threshold_set(hs::thresholds_for(s));
    std::vector<std::uint8_t> rgb;
    for (int i = 0; i < 12; ++i) {
      const ha::Pose2 pose = floor_pose(plan, i);
      renderer.render(pose, seed * 100U + static_cast<std::uint64_t>(i), rgb);
      ha::AreaVector areas;
      ha::segment_rgb24(rgb.data(), s.camera.width_px, s.camera.height_px, s.camera.width_px * 3U,
                        windows, areas);
      ASSERT_TRUE(areas.rows_measured());
      const std::vector<std::uint32_t> seen = renderer.visible_board_pixels(pose);
      for (std::size_t b = 0; b < s.boards.size(); ++b) {
        const hs::BoardImage im = hs::project_board(s.camera, lens, s.boards[b], pose);
        if (im.area_px < 200.0 || std::fabs(seen[b] / im.area_px - 1.0) > 0.02) continue;
        du.push_back(std::fabs(areas.centroid_column_px(b) - im.centroid_u_px));
        dv.push_back(std::fabs(areas.centroid_row_px(b) - im.centroid_v_px));
      }
    }
  }
  ASSERT_GE(du.size(), 40U);
  std::sort(du.begin(), du.end());
  std::sort(dv.begin(), dv.end());
  const std::size_t n = du.size();
  std::printf(
      "centroid |segmented - projected| over %zu boards: column median %.2f p90 %.2f max "
      "%.2f px, row median %.2f p90 %.2f max %.2f px\n",
      n, du[n / 2], du[n * 9 / 10], du[n - 1], dv[n / 2], dv[n * 9 / 10], dv[n - 1]);
  // 0.03 and 0.04 px (median) and 0.10 and 0.19 px (p90) when written, over 123 boards; a row off
  // by one would be a whole pixel.
  EXPECT_LT(du[n / 2], 0.2);
  EXPECT_LT(dv[n / 2], 0.2);
  EXPECT_LT(du[n * 9 / 10], 0.5);
  EXPECT_LT(dv[n * 9 / 10], 0.5);
}

}  // namespace

namespace {

// The law's angle of centroid column @p u_px (forward_map.hpp), the optical axis's offset added.
double law_angle_rad(const hs::ColumnLaw& law, double u_px, std::uint32_t width_px) {
  const double t = (u_px - 0.5 * (width_px - 1.0)) / width_px;
  return law.axis_rad + (law.a1_rad + law.a3_rad * t * t) * t;
}

// The worst difference (degrees) over headings -30..30 degrees between where the law puts a
// small board 4 m away, @p rise_m above the camera (its projected centroid's column), and where
// it is from the camera.
double worst_law_error_deg(const hs::CameraSpec& c, const hs::ColumnLaw& law, double rise_m) {
  const hs::LensModel lens(c);
  hs::BoardSpec b = board_ahead(4.0);
  b.width_m = b.height_m = 0.06;
  b.centre_z_m = c.height_m + rise_m;
  double worst = 0.0;
  for (int deg = -30; deg <= 30; deg += 2) {
    const ha::Pose2 robot{0.0, 0.0, deg * kPi / 180.0};
    const hs::BoardImage image = hs::project_board(c, lens, b, robot);
    if (!(image.area_px > 0.0) || image.cut) continue;
    // The board's direction from the camera's place, as an image angle (positive to the right).
    const double cx = c.forward_offset_m * std::cos(robot.yaw_rad);
    const double cy = c.forward_offset_m * std::sin(robot.yaw_rad);
    const double truth = robot.yaw_rad - std::atan2(b.centre_y_m - cy, b.centre_x_m - cx);
    worst = std::max(worst, std::fabs(law_angle_rad(law, image.centroid_u_px, c.width_px) - truth));
  }
  return worst * 180.0 / kPi;
}

}  // namespace

// The firmware's column-to-angle law from a known camera (lens.hpp; a floor map's law, from the
// fitted camera): on a pinhole it is the arctangent's cubic; the principal point's offset and the
// mounting's yaw go to its axis, not into a1 and a3; with that offset, through a barrel lens and
// from ahead of the axle, where a board appears still gives its direction within a quarter of a
// degree over +-30 degrees. The law has no row: under a pitch it holds for boards seen about the
// frame's middle rows, and one seen lower is off by a few percent of its angle.
TEST(ColumnLaw, TakesTheAxisApartAndGivesTheBoardsDirection) {
  const hs::CameraSpec level = pinhole();
  const hs::ColumnLaw plain = hs::column_law_of(level);
  ASSERT_TRUE(plain.ok);
  EXPECT_NEAR(plain.axis_rad, 0.0, 1e-9);
  EXPECT_NEAR(plain.optical_axis_rad, 0.0, 1e-9);
  // atan(2 tan(35 deg) t) near the centre: slope 2 tan(35 deg) = 1.40.
  EXPECT_NEAR(plain.a1_rad, 2.0 * std::tan(35.0 * kPi / 180.0), 0.05);
  EXPECT_LT(plain.a3_rad, 0.0);  // the arctangent flattens towards the edges
  const double plain_error = worst_law_error_deg(level, plain, 0.0);

  hs::CameraSpec off = level;
  off.principal_offset_x_px = -6.0;  // as -25 px at 1280 (random floor 1)
  off.mount_yaw_deg = 2.0;           // turned to the left: the centre column's ray 2 degrees left
  const hs::ColumnLaw shifted = hs::column_law_of(off);
  ASSERT_TRUE(shifted.ok);
  // The axis: 2 degrees left, and 1.5 degrees right at the centre column; a little less over
  // the columns (the arctangent's slope falls away from the principal point).
  EXPECT_LT(shifted.axis_rad * 180.0 / kPi, std::atan(6.0 / focal_px(off)) * 180.0 / kPi - 2.0);
  EXPECT_GT(shifted.axis_rad * 180.0 / kPi, -2.0);
  // The optical axis under the law: the principal point's 6 px left of the centre column, about
  // atan(6 / f) to the left; the mounting's yaw turns the law's origin and the axis together.
  EXPECT_NEAR(shifted.optical_axis_rad, -std::atan(6.0 / focal_px(off)), 0.2 * kPi / 180.0);
  EXPECT_NEAR(shifted.a1_rad, plain.a1_rad, 0.01 * plain.a1_rad);
  // The offset bends the columns' angles unevenly about the centre, which an odd law cannot
  // follow: a quarter of a degree at 30 degrees.
  EXPECT_LT(worst_law_error_deg(off, shifted, 0.0), 0.3);

  hs::CameraSpec lens = off;
  lens.k1 = -0.17;
  lens.forward_offset_m = 0.18;
  const hs::ColumnLaw lens_law = hs::column_law_of(lens);
  ASSERT_TRUE(lens_law.ok);
  const double lens_error = worst_law_error_deg(lens, lens_law, 0.0);
  hs::ColumnLaw no_axis = lens_law;  // the same law without its axis
  no_axis.axis_rad = 0.0;
  const double no_axis_error = worst_law_error_deg(lens, no_axis, 0.0);

  hs::CameraSpec pitched = lens;
  pitched.pitch_deg = 9.0;
  const hs::ColumnLaw pitched_law = hs::column_law_of(pitched);
  ASSERT_TRUE(pitched_law.ok);
  // Seen on the middle row (4 m away and tan(9 deg) 4 m above the camera), and at the camera's
  // height (36 px lower in the frame).
  const double middle_error =
      worst_law_error_deg(pitched, pitched_law, 4.0 * std::tan(9.0 * kPi / 180.0));
  const double low_error = worst_law_error_deg(pitched, pitched_law, 0.0);
  std::printf(
      "law: pinhole a1 %.4f a3 %.4f, worst %.3f deg; axis %.3f deg; lens a1 %.4f a3 %.4f, "
      "worst %.3f deg (%.3f without its axis); pitched 9 deg: middle row %.3f deg, lower %.3f "
      "deg\n",
      plain.a1_rad, plain.a3_rad, plain_error, shifted.axis_rad * 180.0 / kPi, lens_law.a1_rad,
      lens_law.a3_rad, lens_error, no_axis_error, middle_error, low_error);
  EXPECT_LT(plain_error, 0.1);
  EXPECT_LT(lens_error, 0.3);
  EXPECT_GT(no_axis_error, lens_error + 0.4);
  EXPECT_LT(middle_error, 0.3);
  EXPECT_GT(low_error, 2.0 * middle_error);
  // Fitted at the row where those boards are seen (the trainer passes the rows of its frames'
  // sightings), the law holds there too.
  hs::BoardSpec low_board = board_ahead(4.0);
  low_board.width_m = low_board.height_m = 0.06;
  low_board.centre_z_m = pitched.height_m;
  const hs::BoardImage low_image =
      hs::project_board(pitched, hs::LensModel(pitched), low_board, ha::Pose2{0.0, 0.0, 0.0});
  ASSERT_GT(low_image.area_px, 0.0);
  const double low_row = low_image.centroid_v_px / (pitched.height_px - 1.0);
  EXPECT_GT(low_row, 0.6);  // below the middle rows
  const hs::ColumnLaw low_law = hs::column_law_of(pitched, {low_row});
  ASSERT_TRUE(low_law.ok);
  const double low_fitted_error = worst_law_error_deg(pitched, low_law, 0.0);
  std::printf("pitched 9 deg, the law fitted at row %.3f: lower %.3f deg\n", low_row,
              low_fitted_error);
  EXPECT_LT(low_fitted_error, 0.5 * low_error);
  // Rows outside the frame are not rows: none left, no law.
  EXPECT_FALSE(hs::column_law_of(pitched, {-0.5, 1.5}).ok);
}
