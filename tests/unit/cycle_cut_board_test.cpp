// Boards cut by the frame's side through the whole cycle: a frame of three boards, the red one
// cut by the left side, and a map where the red board's area names another place than the two
// others do. The cycle's fix leaves the cut board out (algorithms::uncut_features) and counts
// the frame; the same frame with the red board clear of the side keeps it.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "one_board_cycle_rig.hpp"

namespace ha = harmoloc::algorithms;
namespace hf = harmoloc::firmware;
using harmoloc::test::one_board::FakeCamera;
using harmoloc::test::one_board::kHeight;
using harmoloc::test::one_board::kWidth;
using harmoloc::test::one_board::NoEncoders;
using harmoloc::test::one_board::StepClock;

namespace {

// Red in columns [red_from, red_from + 4), green in 6..9, blue in 11..13, full height.
std::vector<std::uint8_t> stripes(std::uint32_t red_from) {
  std::vector<std::uint8_t> rgb(kWidth * kHeight * 3, 0);
  for (std::uint32_t y = 0; y < kHeight; ++y) {
    for (std::uint32_t x = 0; x < kWidth; ++x) {
      std::uint8_t* p = &rgb[(y * kWidth + x) * 3];
      if (x >= red_from && x < red_from + 4) p[0] = 255;
      if (x >= 6 && x < 10) p[1] = 255;
      if (x >= 11 && x < 14) p[2] = 255;
    }
  }
  return rgb;
}

// Two training places: at x 1 m green and blue look as in the frame and red shows little; at
// x 3 m red looks as in the frame (25% of it) and the others less.
std::unique_ptr<ha::MapFile> stripe_map() {
  auto m = harmoloc::test::one_board::empty_rig_map();
  ha::HarmonicModel& h = m->model;
  h.sample_count = 2;
  h.feature_count = 3;
  h.board_index = {0, 1, 2};  // red, green, blue
  h.max_nearest_distance = 50.0F;
  const std::array<std::array<float, 3>, 2> features = {
      {{5.0F, 25.0F, 18.75F}, {25.0F, 10.0F, 10.0F}}};
  for (std::size_t i = 0; i < 2; ++i) {
    for (std::size_t k = 0; k < 3; ++k) h.sample(i)[k] = features[i][k];
    h.target_x_m[i] = i == 0 ? 1.0F : 3.0F;
    h.target_y_m[i] = 0.5F;
  }
  return m;
}

struct CutRun {
  double fix_x_m = 0.0;
  std::uint64_t cut_board_frames = 0;
};

CutRun run_frames(std::uint32_t red_from, int frames) {
  const auto map = stripe_map();
  hf::FirmwareConfig config = hf::default_config();
  config.filter.particles = 256;
  FakeCamera camera(stripes(red_from));
  camera.frames = true;
  NoEncoders encoders;
  harmoloc::test::mav::QueueLink link;
  StepClock clock;
  auto cycle = std::make_unique<hf::LocalizationCycle>(config, *map, camera, encoders, link, clock);
  for (int i = 0; i < frames; ++i) cycle->run_once();
  EXPECT_TRUE(cycle->last_fix().present);
  EXPECT_TRUE(cycle->last_fix().fix.known_place);
  return {cycle->last_fix().fix.x_m, cycle->counters().cut_board_frames};
}

}  // namespace

TEST(CycleCutBoard, TheFixLeavesOutABoardTheFramesSideCuts) {
  const CutRun cut = run_frames(0, 3);
  EXPECT_NEAR(cut.fix_x_m, 1.0, 0.05) << "green and blue name x 1 m";
  EXPECT_EQ(cut.cut_board_frames, 3U);

  const CutRun clear = run_frames(1, 3);
  EXPECT_NEAR(clear.fix_x_m, 3.0, 0.05) << "red, seen whole, outweighs the others";
  EXPECT_EQ(clear.cut_board_frames, 0U);
}
