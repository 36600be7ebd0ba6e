// Scenario tests of the particle filter (docs/filter.md): simulated runs replayed through the
// firmware's own cycle, frames rendered in memory, with the bounds of the scenario table
// asserted: a nominal run, a person hiding a board for 3 s, a board moved 30 cm, ten kidnaps.
// The map comes from the scenario.setup fixture (desk-shuttle, training seed 1).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "harmoloc/firmware/map_loader.hpp"
#include "harmoloc/host/log_encoders.hpp"
#include "harmoloc/sim_host/sim_camera.hpp"
#include "scenario_eval.hpp"

namespace hs = harmoloc::sim_host;
namespace ha = harmoloc::algorithms;
namespace hf = harmoloc::firmware;

namespace {

constexpr std::size_t kGreen = 1, kYellow = 3;

const ha::MapFile& map() {
  static const std::unique_ptr<ha::MapFile> m = [] {
    auto out = std::make_unique<ha::MapFile>();
    const char* work = std::getenv("HARMOLOC_SCENARIO_WORK");
    const std::string path = std::string(work != nullptr ? work : ".") + "/desk-shuttle.hmap";
    const std::string e = hf::load_map(path, *out);
    if (!e.empty()) {
      ADD_FAILURE() << e << " (the scenario.setup fixture writes it)";
    }
    return out;
  }();
  return *m;
}

hs::RunRecord replay(const char* scenario, const hf::FirmwareConfig& config,
                     std::uint64_t seed = 2) {
  return hs::replay_scenario(hs::load_scenario(scenario), seed, map(), config);
}

hf::FirmwareConfig robust() {
  return hf::default_config();
}

// Whether board @p b was distrusted in some frame of [from_s, to_s), and in every frame of it.
bool distrusted_some(const hs::RunRecord& r, std::size_t b, double from_s, double to_s) {
  for (const auto& f : r.frames)
    if (f.t_s >= from_s && f.t_s < to_s && (f.distrusted >> b & 1U) != 0) return true;
  return false;
}
// The share of the frames in [from_s, to_s) in which board @p b was distrusted.
double distrusted_share(const hs::RunRecord& r, std::size_t b, double from_s, double to_s) {
  std::size_t n = 0, d = 0;
  for (const auto& f : r.frames) {
    if (f.t_s < from_s || f.t_s >= to_s) continue;
    ++n;
    d += (f.distrusted >> b & 1U) != 0 ? 1U : 0U;
  }
  return n > 0 ? static_cast<double>(d) / static_cast<double>(n) : 0.0;
}

// The time of the last frame in which board @p b was distrusted (0 if none).
double last_distrusted_s(const hs::RunRecord& r, std::size_t b) {
  double last = 0.0;
  for (const auto& f : r.frames)
    if ((f.distrusted >> b & 1U) != 0) last = f.t_s;
  return last;
}

}  // namespace

TEST(FilterScenario, NominalBeatsTheLocalizerAlone) {
  const hs::RunRecord r = replay("desk-shuttle", robust());
  ASSERT_TRUE(r.uses_boards);
  const hs::ErrorStats e = hs::error_stats(r, 3.0, 1e9);
  std::printf("nominal: RMSE %.2f cm, heading %.2f deg, max %.2f cm; localizer alone %.2f cm\n",
              100 * e.rmse_m, e.heading_rmse_deg, 100 * e.max_m, 100 * e.fix_rmse_m);
  EXPECT_LE(e.rmse_m, 0.03);
  EXPECT_LE(e.heading_rmse_deg, 2.0);
  EXPECT_LT(e.rmse_m, e.fix_rmse_m);
  EXPECT_EQ(r.counters.kidnaps, 0U);
  EXPECT_EQ(r.counters.no_consensus, 0U);
}

// A person stands in front of the green board (and most of blue) from 30.1 s to 33.1 s.
TEST(FilterScenario, OccludedBoardIsIgnoredThenTrustedAgain) {
  const hs::RunRecord r = replay("desk-occlusion", robust());
  const hs::ErrorStats e = hs::error_stats(r, 3.0, 1e9);
  const hs::ErrorStats during = hs::error_stats(r, 30.1, 34.5);
  std::printf("occlusion: max %.2f cm (%.2f cm while the person stands there), RMSE %.2f cm\n",
              100 * e.max_m, 100 * during.max_m, 100 * e.rmse_m);
  EXPECT_LE(e.max_m, 0.10);  // the bound
  EXPECT_LE(e.max_m, 0.05);  // what it does today (about 2 cm)
  EXPECT_TRUE(distrusted_some(r, kGreen, 30.1, 33.2)) << "the hidden board was never distrusted";
  EXPECT_FALSE(distrusted_some(r, kGreen, 36.0, 1e9)) << "green not trusted again after 36 s";
  // Before the person comes in (28.7 s) green is trusted nearly throughout: where the test run's
  // wander makes it show a quarter less than the map expects for a second (about 23 s), the
  // motion index may doubt it for a moment.
  std::printf(
      "green distrusted in %.1f%% of the frames before the person comes in, last at %.2f s\n",
      100.0 * distrusted_share(r, kGreen, 0.0, 28.7), last_distrusted_s(r, kGreen));
  EXPECT_LT(distrusted_share(r, kGreen, 0.0, 28.7), 0.05);
  EXPECT_EQ(r.counters.kidnaps, 0U);

  // Without the robust parts the same run drags the estimate further. With the boards' centroid
  // columns in the map (format 12) the fix itself is dragged less, and the margin shrank from
  // over 20% to 8% (2.07 against 1.91 cm, 2026-12-01).
  hf::FirmwareConfig plain = robust();
  plain.observation.boards.robust = false;
  const hs::ErrorStats p = hs::error_stats(replay("desk-occlusion", plain), 30.1, 36.0);
  std::printf("occlusion, not robust: max %.2f cm while the person stands there\n", 100 * p.max_m);
  EXPECT_GT(p.max_m, 1.05 * during.max_m);
}

// The yellow board is moved 30 cm at 29.7 s (and then hides part of green).
TEST(FilterScenario, MovedBoardIsWrittenOffAndTheCameraStaysInUse) {
  const hs::RunRecord r = replay("desk-moved-board", robust());
  const hs::ErrorStats e = hs::error_stats(r, 3.0, 1e9);
  std::printf("moved board: max %.2f cm, RMSE %.2f cm, nominal %llu of %llu cycles\n",
              100 * e.max_m, 100 * e.rmse_m,
              static_cast<unsigned long long>(r.counters.cycles_in_health[1]),
              static_cast<unsigned long long>(r.counters.cycles));
  EXPECT_LE(e.max_m, 0.10);
  EXPECT_LE(e.max_m, 0.05);
  EXPECT_FALSE(distrusted_some(r, kYellow, 0.0, 29.7));
  std::printf("yellow distrusted in %.1f%% of the frames after 32 s\n",
              100.0 * distrusted_share(r, kYellow, 32.0, 1e9));
  EXPECT_GT(distrusted_share(r, kYellow, 32.0, 1e9), 0.9) << "the moved board came back into use";
  EXPECT_GE(r.counters.cycles_in_health[1], r.counters.cycles * 95 / 100);
  EXPECT_EQ(r.counters.kidnaps, 0U);

  // The Gaussian around the harmonic fix survives on dead reckoning: most fixes after the move
  // are off the map, so the camera is lost to it for much of the rest of the run.
  hf::FirmwareConfig fix = robust();
  fix.observation.model = hf::ObservationModel::kFix;
  const hs::RunRecord f = replay("desk-moved-board", fix);
  const hs::ErrorStats fe = hs::error_stats(f, 32.0, 1e9);
  std::printf(
      "moved board, harmonic-fix filter: max %.2f cm after the move, odometry only in "
      "%llu of %llu cycles\n",
      100 * fe.max_m, static_cast<unsigned long long>(f.counters.cycles_in_health[2]),
      static_cast<unsigned long long>(f.counters.cycles));
  EXPECT_GT(f.counters.cycles_in_health[2], f.counters.cycles * 4 / 10);
}

// Ten kidnaps, each >= 1 m along the route: detected and back under 10 cm within 1 s.
TEST(FilterScenario, KidnapsAreDetectedAndRecoveredWithinASecond) {
  const hs::RunRecord r = replay("desk-kidnap", robust());
  const hs::KidnapSummary k = hs::kidnap_summary(r, 0.10, 1.0, 1.0);
  ASSERT_EQ(k.outcomes.size(), 10U);
  for (const auto& o : k.outcomes) {
    std::printf("kidnap at %.1f s, %.2f m: detected after %.2f s, recovered after %.2f s\n", o.t_s,
                o.distance_m, o.detected_after_s, o.recovered_after_s);
  }
  EXPECT_EQ(k.detected, 10U);
  EXPECT_EQ(k.recovered_within, 10U);
  EXPECT_EQ(r.counters.kidnaps, 10U);  // no false alarm in between
}

// A harmonic fix beyond the mapped region (a local linear correction extrapolates; on a random
// floor one lay 2.8 m from the robot, and the re-seed there was published as off the map) is no
// kidnap evidence. With a region no place is inside (a negative margin, which the config refuses
// but the cycle takes), the same ten kidnaps are never confirmed, nor called lost.
TEST(FilterScenario, FixesBeyondTheMappedRegionAreNoKidnapEvidence) {
  hf::FirmwareConfig config = robust();
  config.filter.map_margin_m = -100.0;
  const hs::RunRecord r = replay("desk-kidnap", config);
  EXPECT_GT(r.counters.kidnap_triggers, 0U) << "the change-rate test must still fire";
  EXPECT_EQ(r.counters.kidnaps, 0U);
  EXPECT_EQ(r.counters.lost, 0U);
}

namespace {

// Inputs that go missing in given windows of run time.
struct Window {
  double from_s, to_s;
  bool contains(double t) const { return t >= from_s && t < to_s; }
};

class GappyCamera final : public harmoloc::hal::Camera {
 public:
  GappyCamera(harmoloc::hal::Camera& inner, double t0_s, std::vector<Window> gaps)
      : inner_(inner), t0_s_(t0_s), gaps_(std::move(gaps)) {}
  harmoloc::hal::CameraStatus acquire(harmoloc::hal::FrameView& f,
                                      std::uint64_t deadline) override {
    const harmoloc::hal::CameraStatus s = inner_.acquire(f, deadline);
    if (s != harmoloc::hal::CameraStatus::kFrame) return s;
    const double t = static_cast<double>(f.timestamp_ns) * 1e-9 - t0_s_;
    for (const Window& w : gaps_) {
      if (w.contains(t)) {
        inner_.release();
        return harmoloc::hal::CameraStatus::kNoFrame;
      }
    }
    return s;
  }
  void release() override { inner_.release(); }
  harmoloc::hal::CameraCounters counters() const override { return inner_.counters(); }

 private:
  harmoloc::hal::Camera& inner_;
  double t0_s_;
  std::vector<Window> gaps_;
};

class GappyEncoders final : public harmoloc::hal::WheelEncoders {
 public:
  GappyEncoders(harmoloc::hal::WheelEncoders& inner, double t0_s, std::vector<Window> gaps)
      : inner_(inner), t0_s_(t0_s), gaps_(std::move(gaps)) {}
  harmoloc::hal::EncoderStatus read(std::uint64_t t_ns, harmoloc::hal::EncoderCounts& c) override {
    const harmoloc::hal::EncoderStatus s = inner_.read(t_ns, c);  // drained either way
    const double t = static_cast<double>(t_ns) * 1e-9 - t0_s_;
    for (const Window& w : gaps_) {
      if (w.contains(t) && s == harmoloc::hal::EncoderStatus::kFresh)
        return harmoloc::hal::EncoderStatus::kNoData;
    }
    return s;
  }
  harmoloc::hal::EncoderCounters counters() const override { return inner_.counters(); }

 private:
  harmoloc::hal::WheelEncoders& inner_;
  double t0_s_;
  std::vector<Window> gaps_;
};

class NullLink final : public harmoloc::hal::PoseLink {
 public:
  harmoloc::hal::LinkWrite write_frame(const std::uint8_t*, std::size_t) override {
    return harmoloc::hal::LinkWrite::kSent;
  }
  harmoloc::hal::LinkCounters counters() const override { return {}; }
};

class StepClock final : public harmoloc::hal::Clock {
 public:
  std::uint64_t now_ns() const override { return now_ += 1000; }
  void sleep_until(std::uint64_t) override {}

 private:
  mutable std::uint64_t now_ = 0;
};

}  // namespace

// No frames: odometry only, the covariance grows; no encoder data: vision only; neither: the
// pose is flagged invalid. Each recovers by itself when its input returns.
TEST(FilterScenario, DegradedModesAndRecovery) {
  const hs::Scenario s = hs::load_scenario("desk-shuttle");
  hs::ScenarioRun run(s, 2);
  hf::FirmwareConfig config = robust();
  config.geometry = s.robot;
  config.can_layout = s.can_layout;
  const double t0 = static_cast<double>(run.frame_timestamp_ns(0)) * 1e-9;
  hs::SimCamera sim(run);
  GappyCamera camera(sim, t0, {{8.0, 10.0}, {18.0, 20.0}});
  harmoloc::host::LogEncoders log(run.encoder_frames(), config.can_layout);
  GappyEncoders encoders(log, t0, {{13.0, 15.0}, {18.0, 20.0}});
  NullLink link;
  StepClock clock;
  auto cycle =
      std::make_unique<hf::LocalizationCycle>(config, map(), camera, encoders, link, clock);
  std::vector<std::pair<double, hf::PoseOutput>> out;
  while (cycle->run_once() == hf::CycleResult::kRan) {
    const hf::PoseOutput& p = cycle->pose();
    out.emplace_back(static_cast<double>(p.data_time_ns) * 1e-9 - t0, p);
  }
  const auto at = [&](double t) -> const hf::PoseOutput& {
    for (const auto& [ts, p] : out)
      if (ts >= t) return p;
    return out.back().second;
  };
  const auto truth_error = [&](double t) {
    std::size_t k = 0;
    while (k + 1 < run.frame_count() && run.frame_time_s(k) < t) ++k;
    const hf::PoseOutput& p = at(t);
    return std::hypot(p.pose.x_m - run.truth(k).x_m, p.pose.y_m - run.truth(k).y_m);
  };
  EXPECT_EQ(at(7.5).health, hf::Health::kNominal);
  // Camera gone 8-10 s: odometry only after the timeout, the covariance grows meanwhile.
  EXPECT_EQ(at(8.5).health, hf::Health::kOdometryOnly);
  EXPECT_EQ(at(9.9).health, hf::Health::kOdometryOnly);
  const auto spread = [&](double t) { return at(t).covariance(0, 0) + at(t).covariance(1, 1); };
  EXPECT_GT(spread(9.0), spread(8.3));
  EXPECT_GT(spread(9.9), spread(9.0));
  EXPECT_GT(spread(9.9), 1.3 * spread(8.0));
  EXPECT_LT(spread(10.5), spread(9.9));  // the camera back: it shrinks again
  EXPECT_LT(truth_error(9.9), 0.05);     // dead reckoning holds for 2 s
  EXPECT_EQ(at(10.3).health, hf::Health::kNominal);
  // Encoders gone 13-15 s: vision only.
  EXPECT_EQ(at(13.5).health, hf::Health::kVisionOnly);
  EXPECT_EQ(at(15.3).health, hf::Health::kNominal);
  EXPECT_LT(truth_error(14.9), 0.10);
  // Both gone 18-20 s: invalid; back to nominal after.
  EXPECT_EQ(at(18.5).health, hf::Health::kInvalid);
  EXPECT_EQ(at(20.4).health, hf::Health::kNominal);
  EXPECT_LT(truth_error(22.0), 0.05);
  const auto& c = cycle->counters();
  std::printf("degraded: odometry-only %llu, vision-only %llu, invalid %llu cycles\n",
              static_cast<unsigned long long>(c.cycles_in_health[2]),
              static_cast<unsigned long long>(c.cycles_in_health[3]),
              static_cast<unsigned long long>(c.cycles_in_health[4]));
  EXPECT_EQ(c.kidnaps, 0U);
}
