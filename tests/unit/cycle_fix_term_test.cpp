// The fix term through the whole cycle on the one-board rig with a forward map whose board looks
// the same everywhere: the boards cannot tell places apart, so only the harmonic fix pulls the
// cloud, and how far one frame pulls it says how wide the fix term was there.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "mavlink_test_frames.hpp"
#include "one_board_cycle_rig.hpp"

namespace ha = harmoloc::algorithms;
namespace hf = harmoloc::firmware;
namespace mv = harmoloc::firmware::mavlink;
namespace tf = harmoloc::test::mav;
using harmoloc::test::one_board::calibrated_flat_map;
using harmoloc::test::one_board::kTargets;
using harmoloc::test::one_board::Rig;

namespace {

// The rig's map with a calibration and a flat forward map over 4 m x 4 m (the full red frame
// everywhere), and the per-sample fix error @p fix_error_m at sample 0 (the place a full red
// frame names).
std::unique_ptr<ha::MapFile> flat_map(float fix_error_m) {
  auto map = calibrated_flat_map(100.0F);
  map->model.fix_error_m[0] = fix_error_m;
  return map;
}

// The cloud set 8 cm beside sample 0's place, then one frame whose fix names that place: how
// far the estimate moved towards it (metres).
double pull_of_one_frame(const ha::MapFile& map) {
  Rig r;
  r.cycle =
      std::make_unique<hf::LocalizationCycle>(r.config, map, r.camera, r.encoders, r.link, r.clock);
  const double x = kTargets[0][0], y = kTargets[0][1] + 0.08;
  // LOCAL_FRD: y mirrored.
  r.send_and_run(tf::command(
      mv::kCmdSetPose, {static_cast<float>(x), static_cast<float>(-y), 0, 0.30F, 0.05F, 0, 0}));
  const double before = r.cycle->pose().pose.y_m;
  EXPECT_NEAR(before, y, 0.03);
  r.camera.frames = true;
  r.run();
  EXPECT_EQ(r.cycle->counters().kidnaps, 0U);
  EXPECT_TRUE(r.cycle->pose().valid);
  return before - r.cycle->pose().pose.y_m;
}

}  // namespace

// Where the training run's fixes near a place were 1 cm off, the fix term is as narrow as the
// run's own error and pulls the cloud most of the way; where they were 30 cm off it is ten times
// wider and hardly pulls. Fails if the cycle stops reading the fix error where the fix lands.
TEST(CycleFixTerm, TheFixPullsLessWhereTheMapSaysItsFixesWereWrong) {
  const double narrow = pull_of_one_frame(*flat_map(0.01F));
  const double wide = pull_of_one_frame(*flat_map(0.30F));
  const double none = pull_of_one_frame(*[] {
    auto m = flat_map(0.01F);
    m->model.fix_error_m.fill(0.0F);
    return m;
  }());
  std::printf("pull of one frame: %.4f m (1 cm there), %.4f m (30 cm there), %.4f m (none)\n",
              narrow, wide, none);
  EXPECT_GT(narrow, 0.02);
  EXPECT_LT(wide, 0.3 * narrow);
  EXPECT_NEAR(none, narrow, 0.002);  // 1 cm there is below the run's 3 cm: the same width
}
