// The start-up of the whole cycle on the one-board rig: how wide the first cloud is.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "one_board_cycle_rig.hpp"

namespace ha = harmoloc::algorithms;
namespace hf = harmoloc::firmware;
using harmoloc::test::one_board::Rig;
using harmoloc::test::one_board::test_map;

// The first fix spreads the particles as far as the map's own fix error reaches (its
// calibration), not twice as far: at the end of a route a wider cloud loses its far side to the
// route term and starts off the fix (docs/sweep.md, seed 15's start-up).
TEST(StartUp, TheFirstCloudIsAsWideAsTheFixError) {
  const auto spread_at_first_fix = [](double fix_rmse_m) {
    auto map = std::make_unique<ha::MapFile>(test_map());
    map->calibration.present = true;
    map->calibration.fix_rmse_x_m = map->calibration.fix_rmse_y_m = static_cast<float>(fix_rmse_m);
    Rig r;
    r.camera.frames = true;
    r.cycle = std::make_unique<hf::LocalizationCycle>(r.config, *map, r.camera, r.encoders, r.link,
                                                      r.clock);
    for (int i = 0; i < 5 && !r.cycle->pose().valid; ++i) r.run();
    EXPECT_TRUE(r.cycle->pose().valid);
    const ha::PoseCovariance& c = r.cycle->pose().covariance;
    return std::sqrt(0.5 * (c(0, 0) + c(1, 1)));
  };
  EXPECT_NEAR(spread_at_first_fix(0.10), 0.10, 0.01);
  EXPECT_NEAR(spread_at_first_fix(0.30), 0.30, 0.03);
  EXPECT_NEAR(spread_at_first_fix(0.005), 0.02, 0.002);  // never narrower than 2 cm
}
