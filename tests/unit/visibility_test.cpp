// Visibility (ForwardMap::has_visibility, map version 10): a board's feature at a heading is its
// feature seen whole from the camera's place, times the share of it the lens sees there.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>

#include "harmoloc/algorithms/board_observation.hpp"
#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/particle_filter.hpp"

namespace ha = harmoloc::algorithms;

namespace {

constexpr double kPi = 3.14159265358979323846;

// Board 0 stands at (1.5, 2.0), beyond the grid; its world bearing from (x, y).
double world_bearing(double x, double y) {
  return std::atan2(2.0 - y, 1.5 - x);
}

// A 2 x 1 m grid of 5 cm cells from (1, 0.5); board 0 seen whole shows 2.0 everywhere with an
// angular half-width of 0.05 rad, the lens's half field of view is 0.5 rad. Board 1 gives no
// bearing and keeps its plain feature 0.7; the map's plain feature of board 0 is 1.0 (a mix of
// headings that see it and headings that do not).
std::unique_ptr<ha::ForwardMap> make_visibility_map() {
  auto f = std::make_unique<ha::ForwardMap>();
  EXPECT_TRUE(ha::lay_out_grid(*f, 41, 21));
  f->origin_x_m = 1.0F;
  f->origin_y_m = 0.5F;
  f->cell_m = 0.05F;
  f->board_count = 2;
  f->sigma = {0.05F, 0.05F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F, 0.0F};
  f->has_bearings = true;
  f->bearing_a1_rad = 1.0F;
  f->bearing_sigma_rad[0] = 0.01F;
  f->has_visibility = true;
  for (std::uint32_t r = 0; r < f->rows; ++r) {
    for (std::uint32_t c = 0; c < f->columns; ++c) {
      const std::size_t at = f->index(c, r);
      f->expected[at * ha::kMaxBoards] = 1.0F;
      f->expected[at * ha::kMaxBoards + 1] = 0.7F;
      f->bearing_rad[at * ha::kMaxBoards] =
          static_cast<float>(world_bearing(1.0 + 0.05 * c, 0.5 + 0.05 * r));
      f->bearing_rad[at * ha::kMaxBoards + 1] = ha::ForwardMap::kNoBearing;
      f->heading_terms[(at * ha::kMaxBoards) * 2] = 2.0F;
      f->heading_terms[(at * ha::kMaxBoards) * 2 + 1] = 0.05F;
    }
  }
  return f;
}

std::array<float, ha::kMaxBoards> seen_at(const ha::ForwardMap& map, double x, double y,
                                          double yaw) {
  std::array<float, ha::kMaxBoards> e{};
  ha::expected_at_pose(map, ha::locate(map, x, y), x, y, ha::seen_heading(yaw), e.data());
  return e;
}

}  // namespace

TEST(Visibility, ABoardShowsItsWholeFeatureInViewAndNoneBeyondTheLensEdge) {
  const auto map = make_visibility_map();
  EXPECT_FLOAT_EQ(ha::half_field_of_view(*map), 0.5F);
  const double x = 1.5, y = 0.75, facing = world_bearing(x, y);  // pi / 2
  EXPECT_NEAR(seen_at(*map, x, y, facing)[0], 2.0F, 1e-4F);
  EXPECT_NEAR(seen_at(*map, x, y, facing - 0.3)[0], 2.0F, 1e-4F);
  // Its centre on the frame's edge: half of it.
  EXPECT_NEAR(seen_at(*map, x, y, facing + 0.5)[0], 1.0F, 1e-3F);
  EXPECT_NEAR(seen_at(*map, x, y, facing - 0.5)[0], 1.0F, 1e-3F);
  EXPECT_NEAR(seen_at(*map, x, y, facing + 0.525)[0], 0.5F, 2e-3F);
  // A half-width beyond the edge, and facing away: none.
  EXPECT_NEAR(seen_at(*map, x, y, facing + 0.55)[0], 0.0F, 1e-3F);
  EXPECT_EQ(seen_at(*map, x, y, facing + kPi)[0], 0.0F);
  EXPECT_EQ(seen_at(*map, x, y, facing - kPi)[0], 0.0F);
  // A board without a bearing keeps the cell's feature at every heading.
  for (const double yaw : {facing, facing + kPi})
    EXPECT_FLOAT_EQ(seen_at(*map, x, y, yaw)[1], 0.7F);
  // With an angle gain the board shows more towards the frame's edge: 1 + 0.4 a^2.
  map->visibility_angle_gain = 0.4F;
  EXPECT_NEAR(seen_at(*map, x, y, facing - 0.3)[0], 2.0F * (1.0F + 0.4F * 0.09F), 1e-3F);
  EXPECT_NEAR(seen_at(*map, x, y, facing)[0], 2.0F, 1e-4F);
  // Centred on the optical axis (map version 14): least there, and the same either side of it.
  map->visibility_axis_rad = -0.1F;
  EXPECT_NEAR(seen_at(*map, x, y, facing - 0.1)[0], 2.0F, 1e-4F);
  EXPECT_NEAR(seen_at(*map, x, y, facing - 0.3)[0], 2.0F * (1.0F + 0.4F * 0.04F), 1e-3F);
  EXPECT_NEAR(seen_at(*map, x, y, facing + 0.1)[0], 2.0F * (1.0F + 0.4F * 0.04F), 1e-3F);
  EXPECT_NEAR(seen_at(*map, x, y, facing)[0], 2.0F * (1.0F + 0.4F * 0.01F), 1e-4F);
  map->visibility_axis_rad = 0.0F;
  // A gain that would take it below a quarter is held there.
  map->visibility_angle_gain = -20.0F;
  EXPECT_NEAR(seen_at(*map, x, y, facing - 0.3)[0], 0.5F, 1e-3F);
  map->visibility_angle_gain = 0.0F;
  // Without visibility, the cell's feature.
  map->has_visibility = false;
  EXPECT_FLOAT_EQ(seen_at(*map, x, y, facing + kPi)[0], 1.0F);
}

TEST(Visibility, AHeadingBeyondATurnOrNotANumberStaysBounded) {
  const auto map = make_visibility_map();
  const double x = 1.5, y = 0.75, facing = world_bearing(x, y);
  std::array<float, ha::kMaxBoards> e{};
  const ha::GridPoint at = ha::locate(*map, x, y);
  // The filter's own reading (the particle's yaw as it is): two turns bring it back.
  for (const double yaw : {facing - 2.0 * kPi, facing + 2.0 * kPi}) {
    e.fill(-1.0F);
    ha::apply_visibility(*map, at, static_cast<float>(yaw), e.data());
    EXPECT_NEAR(e[0], 2.0F, 1e-3F) << yaw;
    EXPECT_EQ(e[1], -1.0F);  // no bearing: untouched
  }
  ha::apply_visibility(*map, at, std::nanf(""), e.data());
  EXPECT_EQ(e[0], 0.0F);
  ha::apply_visibility(*map, at, INFINITY, e.data());
  EXPECT_EQ(e[0], 0.0F);
}

// The visibility is read at the camera's place. The robot at (1.5, 0.75), 1.25 m straight in
// front of board 0's wall, faces 65 degrees: from its axle the board lies 25 degrees off the
// axis, within the 28.6-degree half field of view; from its camera 0.3 m ahead it lies 32
// degrees off, beyond the edge by more than the board's half-width.
TEST(Visibility, IsReadAtTheCamerasPlace) {
  const auto map = make_visibility_map();
  const double x = 1.5, y = 0.75, deg = kPi / 180.0, yaw = 65.0 * deg;
  map->bearing_camera_forward_m = 0.3F;
  const double camera_bearing = world_bearing(x + 0.3 * std::cos(yaw), y + 0.3 * std::sin(yaw));
  ASSERT_GT(camera_bearing - yaw, 0.55);
  EXPECT_EQ(seen_at(*map, x, y, yaw)[0], 0.0F);
  EXPECT_NEAR(seen_at(*map, x, y, 90.0 * deg)[0], 2.0F, 1e-3F);
  map->bearing_camera_forward_m = 0.0F;
  ASSERT_LT(world_bearing(x, y) - yaw, 0.45);
  EXPECT_NEAR(seen_at(*map, x, y, yaw)[0], 2.0F, 1e-3F);
}

// In the filter: two particles at one place, one facing the board and one turned away. The
// board seen whole favours the first, the board not seen the second: the heading is observed
// from a board's presence, not only from where it appears.
TEST(Visibility, TheFilterTellsTheHeadingFromWhetherABoardIsInView) {
  const auto map = make_visibility_map();
  const double x = 1.5, y = 0.75, facing = world_bearing(x, y);
  const ha::Pose2 towards{x, y, facing}, away{x, y, ha::wrap_angle_rad(facing + 2.0)};
  const auto ratio = [&](float observed) {
    ha::BoardUpdate u;
    u.map = map.get();
    u.boards = 2;
    u.observed = {observed, 0.7F};
    u.use = {true, true};
    u.gain = {0.9F, 0.9F};
    u.floor = {0.001F, 0.001F};
    u.inv_two_var = {1.0F / (2.0F * 0.05F * 0.05F), 1.0F / (2.0F * 0.05F * 0.05F)};
    ha::ParticleFilter pf;
    pf.configure(100, 3, ha::MotionNoise{});
    pf.initialize_between(towards, away, 0.0, 0.0, false);
    pf.update_boards(u);
    double w_towards = 0.0, w_away = 0.0;
    for (std::size_t i = 0; i < pf.size(); ++i)
      (std::fabs(pf.particle(i).yaw_rad - facing) < 1e-9 ? w_towards : w_away) += pf.weight(i);
    return w_towards / w_away;
  };
  EXPECT_GT(ratio(2.0F), 100.0);
  EXPECT_LT(ratio(0.0F), 0.01);
  // Without visibility both read the cell's feature: no preference.
  map->has_visibility = false;
  EXPECT_NEAR(ratio(2.0F), 1.0, 1e-9);
}
