// A floor map's visibility tables from the fitted geometry (forward_map_geometry.hpp): a board
// whose geometry predicts the frames better takes the geometry's tables, which then predict its
// area at poses and headings no frame was taken from; a board whose kernel tables predict better
// keeps them (rescaled to the geometry's angle gain); a board whose kernel bearings came closer
// keeps those; a map without visibility is left alone.
#include "harmoloc/sim_host/forward_map_geometry.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/projected_bearing.hpp"
#include "harmoloc/algorithms/random.hpp"
#include "harmoloc/sim_host/board_projection.hpp"
#include "harmoloc/sim_host/random_scene.hpp"

namespace hs = harmoloc::sim_host;
namespace ha = harmoloc::algorithms;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr float kKernelBearing = 0.5F, kKernelFeature = 0.123F, kKernelHalfWidth = 0.05F;

struct Fixture {
  hs::CameraSpec camera;
  std::vector<hs::BoardSpec> boards;
  std::unique_ptr<ha::ForwardMap> map = std::make_unique<ha::ForwardMap>();
  hs::SceneGeometryFit fit;
  std::vector<ha::AreaVector> areas;
  std::vector<hs::PlacedFrame> frames;
  float area_scale = 0.0F;
  bool laid_out = false;

  Fixture() {
    camera.width_px = 320;
    camera.height_px = 240;
    camera.horizontal_fov_deg = 70.0;
    camera.k1 = 0.0;  // a pinhole, so that the law below is the lens's own
    camera.pitch_deg = 5.0;
    camera.height_m = 0.45;
    camera.forward_offset_m = 0.1;
    area_scale = 100.0F / static_cast<float>(camera.width_px * camera.height_px);
    hs::BoardSpec a;
    a.name = "a";
    a.centre_x_m = 3.0;
    a.centre_y_m = 0.2;
    a.centre_z_m = 0.5;
    a.width_m = 0.5;
    a.height_m = 0.4;
    a.facing_yaw_rad = kPi;
    hs::BoardSpec b = a;
    b.name = "b";
    b.centre_x_m = 0.3;
    b.centre_y_m = 3.0;
    b.facing_yaw_rad = -kPi / 2.0;
    boards = {a, b};

    // A grid over -1..1 m, both boards, bearings and visibility held.
    laid_out = ha::lay_out_grid(*map, 41, 41);
    map->origin_x_m = -1.0F;
    map->origin_y_m = -1.0F;
    map->cell_m = 0.05F;
    map->board_count = 2;
    map->sigma = {};
    map->sigma[0] = 1.0F;   // the kernel predicts board a badly: the geometry wins
    map->sigma[1] = 1e-6F;  // and board b perfectly: its kernel tables stay
    map->has_bearings = true;
    map->has_visibility = true;
    map->bearing_camera_forward_m = static_cast<float>(camera.forward_offset_m);
    map->bearing_sigma_rad[0] = map->bearing_sigma_rad[1] = 0.01F;
    // The pinhole's law, angle = atan(2 t tan(fov / 2)), as a1 t + a3 t^3 by least squares.
    const double k = std::tan(0.5 * camera.horizontal_fov_deg * kPi / 180.0);
    double s11 = 0, s13 = 0, s33 = 0, r1 = 0, r3 = 0;
    for (int i = -50; i <= 50; ++i) {
      const double t = 0.01 * i, y = std::atan(2.0 * t * k);
      s11 += t * t;
      s13 += t * t * t * t;
      s33 += t * t * t * t * t * t;
      r1 += t * y;
      r3 += t * t * t * y;
    }
    const double det = s11 * s33 - s13 * s13;
    map->bearing_a1_rad = static_cast<float>((r1 * s33 - r3 * s13) / det);
    map->bearing_a3_rad = static_cast<float>((s11 * r3 - s13 * r1) / det);
    for (std::size_t at = 0; at < map->stored_cells(); ++at) {
      for (std::size_t bd = 0; bd < 2; ++bd) {
        map->bearing_rad[at * ha::kMaxBoards + bd] = kKernelBearing;
        map->heading_terms[(at * ha::kMaxBoards + bd) * 2] = kKernelFeature;
        map->heading_terms[(at * ha::kMaxBoards + bd) * 2 + 1] = kKernelHalfWidth;
      }
    }

    fit.ok = true;
    fit.camera = camera;
    for (const hs::BoardSpec& s : boards) {
      hs::BoardFit f;
      f.ok = true;
      f.board = s;
      fit.boards.push_back(f);
    }

    // Frames from the projection at random poses and headings over the grid.
    ha::Pcg32 rng(7);
    const hs::LensModel lens(camera);
    for (std::size_t i = 0; i < 400; ++i) {
      const ha::Pose2 pose{rng.uniform(-0.9, 0.9), rng.uniform(-0.9, 0.9), rng.uniform(-kPi, kPi)};
      ha::AreaVector v;
      v.count = 2;
      v.width_px = camera.width_px;
      v.height_px = camera.height_px;
      for (std::size_t bd = 0; bd < 2; ++bd) {
        const hs::BoardImage im = hs::project_board(camera, lens, boards[bd], pose);
        // The projection does not know the face from the back; the renderer shows the back grey.
        const ha::Pose2 cam{pose.x_m + camera.forward_offset_m * std::cos(pose.yaw_rad),
                            pose.y_m + camera.forward_offset_m * std::sin(pose.yaw_rad), 0.0};
        const hs::BoardAxes ax = hs::board_axes(boards[bd]);
        const bool face = (cam.x_m - boards[bd].centre_x_m) * ax.normal[0] +
                              (cam.y_m - boards[bd].centre_y_m) * ax.normal[1] >
                          0.0;
        if (!face || !(im.area_px > 0.0)) continue;
        v.pixels[bd] = static_cast<std::uint32_t>(std::lround(im.area_px));
        v.column_sum[bd] =
            static_cast<std::uint64_t>(std::llround(im.centroid_u_px * v.pixels[bd]));
        v.row_sum[bd] = static_cast<std::uint64_t>(std::llround(im.centroid_v_px * v.pixels[bd]));
        const bool side = im.centroid_u_px - 0.6 * std::sqrt(im.area_px) < 0.0 ||
                          im.centroid_u_px + 0.6 * std::sqrt(im.area_px) > camera.width_px - 1.0;
        v.side_pixels[bd] = im.cut && side ? 1U : 0U;
      }
      hs::PlacedFrame f;
      f.index = areas.size();
      f.t_s = 0.1 * static_cast<double>(i);
      f.pose = pose;
      frames.push_back(f);
      areas.push_back(v);
    }
  }

  // Board @p b's feature the map expects at @p pose (as the firmware reads it).
  float expected(std::size_t b, const ha::Pose2& pose) const {
    float out[ha::kMaxBoards] = {};
    const ha::SeenHeading h = ha::seen_heading(pose.yaw_rad);
    ha::expected_at_pose(*map, ha::locate(*map, pose.x_m, pose.y_m), pose.x_m, pose.y_m, h, out);
    return out[b];
  }
  float projected(std::size_t b, const ha::Pose2& pose) const {
    const hs::LensModel lens(camera);
    return static_cast<float>(hs::project_board(camera, lens, boards[b], pose).area_px) *
           area_scale;
  }
};

}  // namespace

TEST(ForwardMapGeometry, TheBetterBoardTakesTheGeometryAndPredictsPosesNoFrameSaw) {
  Fixture fx;
  ASSERT_TRUE(fx.laid_out);
  const hs::GeometryTablesReport r =
      hs::visibility_from_geometry(fx.fit, fx.areas, fx.frames, fx.area_scale, *fx.map);
  ASSERT_TRUE(r.applied) << r.skipped;
  ASSERT_EQ(r.from_geometry.size(), 2U);
  EXPECT_EQ(r.from_geometry[0], 1);
  EXPECT_EQ(r.from_geometry[1], 0);
  EXPECT_GT(r.cells, 1000U);
  // Board a's noise is the geometry's over the frames: small against its features (about 1 to
  // 4 units here), and the map's noise is now that.
  EXPECT_GT(r.geometry_sigma[0], 0.0);
  EXPECT_LT(r.geometry_sigma[0], 0.1);
  EXPECT_FLOAT_EQ(fx.map->sigma[0], static_cast<float>(r.geometry_sigma[0]));
  EXPECT_LT(r.geometry_bearing_sigma_rad[0], 0.01);
  EXPECT_EQ(r.kernel_bearings[0], 0);  // the kernel's spread is 0.01 rad: the geometry's kept
  EXPECT_FLOAT_EQ(fx.map->bearing_sigma_rad[0],
                  static_cast<float>(r.geometry_bearing_sigma_rad[0]));

  // Poses and headings no frame had, the board seen whole at an angle, cut by the frame's edge,
  // and from behind the camera: within 5% of the projection (the table is bilinear on a 5 cm
  // grid, the law a cubic fit of the pinhole's), 0 when it is out of view.
  const ha::Pose2 whole{0.33, -0.41, 0.25};
  const float p_whole = fx.projected(0, whole);
  ASSERT_GT(p_whole, 0.5F);
  EXPECT_NEAR(fx.expected(0, whole), p_whole, 0.05F * p_whole);
  const ha::Pose2 away{-0.27, 0.52, kPi};
  EXPECT_EQ(fx.projected(0, away), 0.0F);
  EXPECT_NEAR(fx.expected(0, away), 0.0F, 1e-3F);
  const ha::Pose2 straight{0.61, 0.07, 0.0};
  EXPECT_NEAR(fx.expected(0, straight), fx.projected(0, straight),
              0.03F * fx.projected(0, straight));

  // The map's angle gain is the geometry's: a pinhole stretches a board at image angle a by
  // about 1 / cos^3 a = 1 + 1.5 a^2 + ...
  EXPECT_GT(r.geometry_angle_gain, 1.2);
  EXPECT_LT(r.geometry_angle_gain, 2.0);
  EXPECT_FLOAT_EQ(fx.map->visibility_angle_gain, static_cast<float>(r.geometry_angle_gain));

  // Board b keeps its kernel tables: the bearings and widths to the bit, the features scaled
  // from the kernel's gain (0 here) to the geometry's by one factor (within 1 / (1 + gain a^2)
  // at the frame's edge and 1), and its noise.
  const float scaled = fx.map->heading_terms[ha::kMaxBoards * 0 + 1 * 2];
  EXPECT_LT(scaled, kKernelFeature);
  EXPECT_GT(scaled, 0.7F * kKernelFeature);
  for (std::size_t at = 0; at < fx.map->stored_cells(); ++at) {
    ASSERT_EQ(fx.map->bearing_rad[at * ha::kMaxBoards + 1], kKernelBearing);
    ASSERT_EQ(fx.map->heading_terms[(at * ha::kMaxBoards + 1) * 2], scaled);
    ASSERT_EQ(fx.map->heading_terms[(at * ha::kMaxBoards + 1) * 2 + 1], kKernelHalfWidth);
  }
  EXPECT_EQ(fx.map->sigma[1], 1e-6F);
}

TEST(ForwardMapGeometry, LeavesAMapWithoutVisibilityOrAFailedFitAlone) {
  Fixture fx;
  ASSERT_TRUE(fx.laid_out);
  fx.map->has_visibility = false;
  hs::GeometryTablesReport r =
      hs::visibility_from_geometry(fx.fit, fx.areas, fx.frames, fx.area_scale, *fx.map);
  EXPECT_FALSE(r.applied);
  EXPECT_NE(r.skipped.find("visibility"), std::string::npos);
  fx.map->has_visibility = true;
  fx.fit.ok = false;
  r = hs::visibility_from_geometry(fx.fit, fx.areas, fx.frames, fx.area_scale, *fx.map);
  EXPECT_FALSE(r.applied);
  EXPECT_NE(r.skipped.find("fit"), std::string::npos);
  for (std::size_t at = 0; at < fx.map->stored_cells(); ++at) {
    ASSERT_EQ(fx.map->bearing_rad[at * ha::kMaxBoards], kKernelBearing);
    ASSERT_EQ(fx.map->heading_terms[at * ha::kMaxBoards * 2], kKernelFeature);
  }
  EXPECT_EQ(fx.map->sigma[0], 1.0F);
}

TEST(ForwardMapGeometry, KeepsTheKernelsBearingsWhereTheyCameCloser) {
  Fixture fx;
  ASSERT_TRUE(fx.laid_out);
  fx.map->bearing_sigma_rad[0] = 1e-4F;  // tighter than the geometry's can be (0.1 degree at least)
  const hs::GeometryTablesReport r =
      hs::visibility_from_geometry(fx.fit, fx.areas, fx.frames, fx.area_scale, *fx.map);
  ASSERT_EQ(r.from_geometry[0], 1);
  EXPECT_EQ(r.kernel_bearings[0], 1);
  EXPECT_EQ(fx.map->bearing_sigma_rad[0], 1e-4F);
  // The bearings are the kernel's, the areas and widths the geometry's.
  bool geometry_features = false;
  for (std::size_t at = 0; at < fx.map->stored_cells(); ++at) {
    ASSERT_EQ(fx.map->bearing_rad[at * ha::kMaxBoards], kKernelBearing);
    geometry_features =
        geometry_features || fx.map->heading_terms[at * ha::kMaxBoards * 2] != kKernelFeature;
  }
  EXPECT_TRUE(geometry_features);
}

namespace {

// A geometry fit that found @p scene's true camera and boards.
hs::SceneGeometryFit true_fit(const hs::Scenario& scene) {
  hs::SceneGeometryFit fit;
  fit.ok = true;
  fit.camera = scene.camera;
  for (const hs::BoardSpec& b : scene.boards) {
    hs::BoardFit f;
    f.ok = true;
    f.board = b;
    fit.boards.push_back(f);
  }
  return fit;
}

// The box the boards' centres span on the floor, where the tests draw poses.
struct BoardBox {
  double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
};
BoardBox board_box(const hs::Scenario& scene) {
  BoardBox box;
  for (const hs::BoardSpec& b : scene.boards) {
    box.lo_x = std::min(box.lo_x, b.centre_x_m);
    box.hi_x = std::max(box.hi_x, b.centre_x_m);
    box.lo_y = std::min(box.lo_y, b.centre_y_m);
    box.hi_y = std::max(box.hi_y, b.centre_y_m);
  }
  return box;
}

}  // namespace

// The projected bearings (map version 15, projected_bearing.hpp) from the true camera and boards
// of random scenes: the firmware's projection of a board's few outline points must find the
// centroid column that the 48-point outline gives (board_projection.hpp), for every pose from
// which a board is seen whole. Its outline's corners exactly where the geometry puts them; its
// polygon's centroid within a few pixels (a lens bends the edges between the corners).
TEST(ProjectedBearing, FindsTheOutlinesCentroidColumnFromAnyPose) {
  for (const std::uint64_t seed : {1U, 5U, 8U}) {
    const hs::Scenario scene = hs::random_scenario(seed);
    const hs::SceneGeometryFit fit = true_fit(scene);
    auto map = std::make_unique<ha::ForwardMap>();
    map->has_bearings = true;
    map->board_count = static_cast<std::uint32_t>(scene.boards.size());
    for (std::size_t b = 0; b < scene.boards.size(); ++b) map->bearing_sigma_rad[b] = 0.01F;
    std::vector<char> boards(scene.boards.size(), 1);
    boards[0] = 0;  // left to the tables
    ASSERT_EQ(hs::project_bearings_from_geometry(fit, boards, *map), scene.boards.size() - 1);
    const ha::BearingProjection& p = map->projection;
    EXPECT_EQ(p.points[0], 0U);
    const hs::LensModel lens(scene.camera);
    const BoardBox box = board_box(scene);
    std::mt19937 rng(static_cast<unsigned>(seed));
    std::uniform_real_distribution<double> ux(box.lo_x, box.hi_x), uy(box.lo_y, box.hi_y),
        uyaw(-kPi, kPi);
    std::vector<double> miss_px;
    std::size_t corner_checks = 0;
    for (int i = 0; i < 3000; ++i) {
      const ha::Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
      const ha::CameraAtPose at = ha::camera_at_pose(
          p, static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
          static_cast<float>(std::cos(pose.yaw_rad)), static_cast<float>(std::sin(pose.yaw_rad)));
      for (std::size_t b = 1; b < scene.boards.size(); ++b) {
        const hs::BoardImage image = hs::project_board(scene.camera, lens, scene.boards[b], pose);
        float column = 0.0F;
        const bool seen = ha::projected_centroid_column(p, at, b, column);
        if (!(image.area_px > 100.0) || image.cut) continue;
        // Seen whole by the outline, the corners are in the frame too (but for a pixel's rounding
        // where the lens bends an edge outwards).
        if (!seen) continue;
        miss_px.push_back(std::fabs(static_cast<double>(column) - image.centroid_u_px));
        // The first outline point alone, as a tiny board at that corner would show it.
        if (corner_checks < 50) {
          hs::BoardSpec dot = scene.boards[b];
          dot.centre_x_m = p.point_m(b, 0, 0);
          dot.centre_y_m = p.point_m(b, 0, 1);
          dot.centre_z_m = p.point_m(b, 0, 2);
          dot.width_m = dot.height_m = 1e-4;
          const hs::BoardImage point = hs::project_board(scene.camera, lens, dot, pose);
          // A 3 mm triangle in the board's plane about the corner: the mean of its projected
          // vertices (the centroid of a triangle) is the corner's projection, to 0.01 px.
          ha::BearingProjection one = p;
          one.points = {};
          one.points[b] = 3;
          const hs::BoardAxes axes = hs::board_axes(scene.boards[b]);
          for (std::size_t d = 0; d < 3; ++d) {
            const auto w = static_cast<float>(3e-3 * axes.width_dir[d]);
            const auto h = static_cast<float>(3e-3 * axes.height_dir[d]);
            const float c = p.point_m(b, 0, d);
            one.point_m(b, 0, d) = c + w;
            one.point_m(b, 1, d) = c + h;
            one.point_m(b, 2, d) = c - w - h;
          }
          float single = 0.0F;
          if (point.area_px > 0.0 && !point.cut &&
              ha::projected_centroid_column(one, at, b, single)) {
            EXPECT_NEAR(single, point.centroid_u_px, 0.05) << "seed " << seed << " board " << b;
            ++corner_checks;
          }
        }
      }
    }
    ASSERT_GT(miss_px.size(), 200U) << "seed " << seed;
    EXPECT_GT(corner_checks, 10U) << "seed " << seed;
    std::sort(miss_px.begin(), miss_px.end());
    const double median = miss_px[miss_px.size() / 2];
    const double p90 = miss_px[miss_px.size() * 9 / 10];
    std::printf("seed %llu: %zu views, centroid column missed by %.3f px median, %.3f px p90\n",
                static_cast<unsigned long long>(seed), miss_px.size(), median, p90);
    EXPECT_LT(median, 1.0) << "seed " << seed;
    EXPECT_LT(p90, 3.0) << "seed " << seed;
  }
}

// The projection's own spread (map version 16, projected_bearing_spread): frames whose measured
// centroid column is the projected one plus Gaussian noise of 2 px give a spread of that noise
// through the law (1.4826 times the median absolute miss is the noise's sigma); a board without
// an outline, and any board with fewer than 20 frames that give its bearing, get none.
TEST(ProjectedBearing, SpreadIsTheMissAgainstTheFramesAtTheirPoses) {
  const hs::Scenario scene = hs::random_scenario(5);
  const hs::SceneGeometryFit fit = true_fit(scene);
  auto map = std::make_unique<ha::ForwardMap>();
  map->has_bearings = true;
  map->board_count = static_cast<std::uint32_t>(scene.boards.size());
  map->bearing_a1_rad = 1.2F;  // a straight law: a1 / w radians a pixel across the frame
  for (std::size_t b = 0; b < scene.boards.size(); ++b) map->bearing_sigma_rad[b] = 0.01F;
  std::vector<char> boards(scene.boards.size(), 1);
  boards[0] = 0;  // left to the tables
  ASSERT_GT(hs::project_bearings_from_geometry(fit, boards, *map), 1U);
  const ha::BearingProjection& p = map->projection;
  const double w = p.width_px;
  const BoardBox box = board_box(scene);
  constexpr double kNoisePx = 2.0;
  constexpr std::uint32_t kPixels = 4000;
  std::mt19937 rng(5U);
  std::uniform_real_distribution<double> ux(box.lo_x, box.hi_x), uy(box.lo_y, box.hi_y),
      uyaw(-kPi, kPi);
  std::normal_distribution<double> noise(0.0, kNoisePx);
  std::vector<ha::AreaVector> areas;
  std::vector<hs::PlacedFrame> frames;
  std::vector<std::size_t> seen(scene.boards.size(), 0);
  for (int i = 0; i < 8000; ++i) {
    const ha::Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    const ha::CameraAtPose at = ha::camera_at_pose(
        p, static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
        static_cast<float>(std::cos(pose.yaw_rad)), static_cast<float>(std::sin(pose.yaw_rad)));
    ha::AreaVector a;
    a.width_px = p.width_px;
    a.height_px = p.height_px;
    a.count = scene.boards.size();
    bool any = false;
    for (std::size_t b = 0; b < scene.boards.size(); ++b) {
      float column = 0.0F;
      // Board 0 is measured from where its outline would be, so that only the missing outline
      // keeps it out.
      const ha::BearingProjection& from = b == 0 ? ha::BearingProjection{} : p;
      if (b == 0 || !ha::projected_centroid_column(from, at, b, column)) continue;
      if (static_cast<double>(column) < 0.1 * w || static_cast<double>(column) > 0.9 * w) continue;
      const double measured = static_cast<double>(column) + noise(rng);
      a.pixels[b] = kPixels;
      a.column_sum[b] = static_cast<std::uint64_t>(std::llround(measured * kPixels));
      ++seen[b];
      any = true;
    }
    if (!any) continue;
    hs::PlacedFrame f;
    f.index = areas.size();
    f.pose = pose;
    frames.push_back(f);
    areas.push_back(a);
  }
  const std::vector<double> spread = hs::projected_bearing_spread(*map, areas, frames);
  ASSERT_EQ(spread.size(), scene.boards.size());
  EXPECT_EQ(spread[0], 0.0);
  std::size_t checked = 0;
  double sum = 0.0;
  for (std::size_t b = 1; b < scene.boards.size(); ++b) {
    if (p.points[b] == 0U || seen[b] < 500) continue;
    // Over a thousand frames or more the estimate's own spread is about 4%: within 15% (the
    // median absolute miss without its factor would be 33% low).
    const double expected = kNoisePx * static_cast<double>(map->bearing_a1_rad) / w;
    EXPECT_NEAR(spread[b], expected, 0.15 * expected) << "board " << b << ", " << seen[b];
    sum += spread[b] / expected;
    ++checked;
  }
  ASSERT_GE(checked, 2U);
  EXPECT_NEAR(sum / static_cast<double>(checked), 1.0, 0.06);
  // Fewer than 20 frames: no spread for any board.
  const std::vector<hs::PlacedFrame> few(frames.begin(), frames.begin() + 19);
  for (const double s : hs::projected_bearing_spread(*map, areas, few)) EXPECT_EQ(s, 0.0);
}

namespace {

// The relative misses of the firmware's projected area (projected_area_px) against the renderer's
// closed form (project_board, 48 outline points) for @p scene's boards 1.. from random poses:
// views the frame shows whole in @p whole, views its border cuts in @p cut (both at least 100 px
// by the renderer); in @p unprojected the views it gives no area for.
void area_misses(const hs::Scenario& scene, std::uint64_t seed, std::vector<double>& whole,
                 std::vector<double>& cut, std::size_t& unprojected) {
  const hs::SceneGeometryFit fit = true_fit(scene);
  auto map = std::make_unique<ha::ForwardMap>();
  map->has_bearings = true;
  map->board_count = static_cast<std::uint32_t>(scene.boards.size());
  for (std::size_t b = 0; b < scene.boards.size(); ++b) map->bearing_sigma_rad[b] = 0.01F;
  std::vector<char> boards(scene.boards.size(), 1);
  boards[0] = 0;
  ASSERT_EQ(hs::project_bearings_from_geometry(fit, boards, *map), scene.boards.size() - 1);
  const ha::BearingProjection& p = map->projection;
  float none = 1.0F;
  EXPECT_FALSE(ha::projected_area_px(p, ha::camera_at_pose(p, 0.0F, 0.0F, 1.0F, 0.0F), 0, none));
  const hs::LensModel lens(scene.camera);
  const BoardBox box = board_box(scene);
  std::mt19937 rng(static_cast<unsigned>(seed));
  std::uniform_real_distribution<double> ux(box.lo_x, box.hi_x), uy(box.lo_y, box.hi_y),
      uyaw(-kPi, kPi);
  for (int i = 0; i < 3000; ++i) {
    const ha::Pose2 pose{ux(rng), uy(rng), uyaw(rng)};
    const ha::CameraAtPose at = ha::camera_at_pose(
        p, static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
        static_cast<float>(std::cos(pose.yaw_rad)), static_cast<float>(std::sin(pose.yaw_rad)));
    for (std::size_t b = 1; b < scene.boards.size(); ++b) {
      const hs::BoardImage image = hs::project_board(scene.camera, lens, scene.boards[b], pose);
      float area = -1.0F;
      if (!ha::projected_area_px(p, at, b, area)) {
        // Partly behind the camera or beyond the lens's image: the renderer's view is cut.
        EXPECT_TRUE(image.cut || image.area_px == 0.0) << "seed " << seed << " board " << b;
        ++unprojected;
        continue;
      }
      ASSERT_TRUE(area >= 0.0F && std::isfinite(area));
      if (!(image.area_px > 100.0)) continue;
      (image.cut ? cut : whole)
          .push_back(std::fabs(static_cast<double>(area) - image.area_px) / image.area_px);
    }
  }
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

}  // namespace

// The projected areas (map version 17): the firmware's eight outline points, projected and
// clipped to the frame, give the area the renderer's 48-point outline gives, from any pose: the
// whole views of random scenes within about 1% (the lens bends the sides between the points),
// the views the frame's border cuts within a few percent.
TEST(ProjectedArea, IsTheRenderersAreaFromAnyPose) {
  std::size_t unprojected_views = 0;
  for (const std::uint64_t seed : {1U, 5U, 8U}) {
    const hs::Scenario scene = hs::random_scenario(seed);
    std::vector<double> whole, cut;
    std::size_t unprojected = 0;
    area_misses(scene, seed, whole, cut, unprojected);
    ASSERT_GT(whole.size(), 200U) << "seed " << seed;
    ASSERT_GT(cut.size(), 50U) << "seed " << seed;
    std::printf(
        "seed %llu: %zu whole views missed by %.3f%% median, %.3f%% p90; %zu cut by the frame "
        "%.3f%% median, %.3f%% p90; %zu views partly unprojected\n",
        static_cast<unsigned long long>(seed), whole.size(), 100.0 * quantile(whole, 0.5),
        100.0 * quantile(whole, 0.9), cut.size(), 100.0 * quantile(cut, 0.5),
        100.0 * quantile(cut, 0.9), unprojected);
    EXPECT_LT(quantile(whole, 0.5), 0.01) << "seed " << seed;
    EXPECT_LT(quantile(whole, 0.9), 0.02) << "seed " << seed;
    EXPECT_LT(quantile(cut, 0.5), 0.02) << "seed " << seed;
    EXPECT_LT(quantile(cut, 0.9), 0.10) << "seed " << seed;
    unprojected_views += unprojected;
  }
  // Views the outline cannot follow occur (and gave the renderer's cut or empty view).
  EXPECT_GT(unprojected_views, 0U);
}

// Through a lens without distortion a rectangle's sides stay straight, so its outline's points
// give the renderer's area exactly (float's rounding aside), whole or cut by the frame.
TEST(ProjectedArea, IsExactForAPinholeAndRectangles) {
  hs::Scenario scene = hs::random_scenario(5);
  scene.camera.k1 = scene.camera.k2 = scene.camera.k3 = 0.0;
  scene.camera.p1 = scene.camera.p2 = 0.0;
  for (hs::BoardSpec& b : scene.boards) b.shape = hs::BoardShape::kRectangle;
  std::vector<double> whole, cut;
  std::size_t unprojected = 0;
  area_misses(scene, 5, whole, cut, unprojected);
  ASSERT_GT(whole.size(), 200U);
  ASSERT_GT(cut.size(), 50U);
  EXPECT_LT(quantile(whole, 1.0), 1e-3);
  EXPECT_LT(quantile(cut, 0.99), 1e-3);
}

// A board wholly behind the camera shows nothing; a view of it that the outline cannot follow
// gives no area.
TEST(ProjectedArea, NothingBehindTheCamera) {
  const hs::Scenario scene = hs::random_scenario(5);
  auto map = std::make_unique<ha::ForwardMap>();
  map->has_bearings = true;
  map->board_count = static_cast<std::uint32_t>(scene.boards.size());
  for (std::size_t b = 0; b < scene.boards.size(); ++b) map->bearing_sigma_rad[b] = 0.01F;
  ASSERT_GT(hs::project_bearings_from_geometry(true_fit(scene),
                                               std::vector<char>(scene.boards.size(), 1), *map),
            0U);
  const ha::BearingProjection& p = map->projection;
  const hs::BoardSpec& board = scene.boards[1];
  // Two metres in front of the board's face, facing away from it.
  const double nx = std::cos(board.facing_yaw_rad), ny = std::sin(board.facing_yaw_rad);
  const ha::Pose2 pose{board.centre_x_m + 2.0 * nx, board.centre_y_m + 2.0 * ny,
                       board.facing_yaw_rad};
  const ha::CameraAtPose away = ha::camera_at_pose(
      p, static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
      static_cast<float>(std::cos(pose.yaw_rad)), static_cast<float>(std::sin(pose.yaw_rad)));
  float area = -1.0F;
  ASSERT_TRUE(ha::projected_area_px(p, away, 1, area));
  EXPECT_EQ(area, 0.0F);
  // Turned round to face it, the board shows.
  const ha::CameraAtPose facing =
      ha::camera_at_pose(p, static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
                         static_cast<float>(std::cos(pose.yaw_rad + kPi)),
                         static_cast<float>(std::sin(pose.yaw_rad + kPi)));
  ASSERT_TRUE(ha::projected_area_px(p, facing, 1, area));
  EXPECT_GT(area, 100.0F);
}

// A board offered an outline for its areas alone (its tables stayed the kernel's) keeps it only
// where the projection took its areas; the boards whose tables the geometry serves keep theirs.
TEST(ProjectedArea, OutlinesOfferedForTheAreasAloneGoWhereTheAreasWereNotTaken) {
  const hs::Scenario scene = hs::random_scenario(5);
  ASSERT_GE(scene.boards.size(), 4U);
  auto map = std::make_unique<ha::ForwardMap>();
  map->has_bearings = true;
  map->board_count = static_cast<std::uint32_t>(scene.boards.size());
  for (std::size_t b = 0; b < scene.boards.size(); ++b) map->bearing_sigma_rad[b] = 0.01F;
  const std::vector<char> all(scene.boards.size(), 1);
  ASSERT_EQ(hs::project_bearings_from_geometry(true_fit(scene), all, *map), scene.boards.size());
  ha::BearingProjection& p = map->projection;
  for (std::size_t b = 0; b < scene.boards.size(); ++b) p.sigma_rad[b] = 0.002F;
  p.area_per_px[1] = p.area_per_px[3] = 1e-4F;  // taken
  p.area_sigma[1] = p.area_sigma[3] = 0.01F;
  std::vector<char> served(scene.boards.size(), 0);
  served[0] = 1;  // its tables from the geometry: keeps its outline for its bearings
  const ha::BearingProjection before = p;
  EXPECT_EQ(hs::drop_untaken_outlines(served, *map), scene.boards.size() - 3);
  for (const std::size_t b : {0U, 1U, 3U}) {
    EXPECT_EQ(p.points[b], before.points[b]) << b;
    EXPECT_EQ(p.sigma_rad[b], before.sigma_rad[b]) << b;
    EXPECT_EQ(p.point_m(b, 0, 0), before.point_m(b, 0, 0)) << b;
  }
  EXPECT_EQ(p.area_per_px[1], 1e-4F);
  for (std::size_t b = 4; b < scene.boards.size(); ++b) EXPECT_EQ(p.points[b], 0U) << b;
  EXPECT_EQ(p.points[2], 0U);
  EXPECT_EQ(p.sigma_rad[2], 0.0F);
  for (std::size_t i = 0; i < ha::BearingProjection::kMaxPoints; ++i)
    EXPECT_EQ(p.point_m(2, i, 2), 0.0F) << i;
  EXPECT_TRUE(p.present());
  EXPECT_EQ(p.focal_px, before.focal_px);

  // None served and none taken: no projection at all.
  p.area_per_px[1] = p.area_per_px[3] = 0.0F;
  EXPECT_EQ(hs::drop_untaken_outlines(std::vector<char>(scene.boards.size(), 0), *map), 3U);
  EXPECT_FALSE(p.present());
  EXPECT_EQ(p.focal_px, 0.0F);
}
