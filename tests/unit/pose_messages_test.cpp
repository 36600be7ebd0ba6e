// The outbound mapping of the wire protocol (firmware/pose_messages.hpp): the map frame's pose
// in MAV_FRAME_LOCAL_FRD, the covariance's signs, the quality, and what each health says.
#include "harmoloc/firmware/pose_messages.hpp"

#include "harmoloc/firmware/mavlink_parser.hpp"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

namespace hf = harmoloc::firmware;
namespace mav = harmoloc::firmware::mavlink;

namespace {

hf::PoseOutput pose_at(double x_m, double y_m, double yaw_rad) {
  hf::PoseOutput p;
  p.pose = harmoloc::algorithms::Pose2{x_m, y_m, yaw_rad};
  p.health = hf::Health::kNominal;
  p.valid = true;
  return p;
}

}  // namespace

TEST(PoseMessages, OdometryIsInTheFrdFrame) {
  hf::PoseOutput p = pose_at(1.5, 2.0, 0.5);
  p.speed_mps = 0.3;
  p.yaw_rate_rps = 0.2;
  const mav::Odometry m = hf::odometry_message(p, 1'234'567'891, 7);
  EXPECT_EQ(m.time_usec, 1'234'567U);
  EXPECT_FLOAT_EQ(m.x, 1.5F);
  EXPECT_FLOAT_EQ(m.y, -2.0F);  // y flips (z down)
  EXPECT_FLOAT_EQ(m.z, 0.0F);
  // yaw 0.5 rad counter-clockwise is -0.5 rad about the downward z: q = (cos -0.25, 0, 0, sin
  // -0.25)
  EXPECT_FLOAT_EQ(m.q[0], static_cast<float>(std::cos(-0.25)));
  EXPECT_FLOAT_EQ(m.q[3], static_cast<float>(std::sin(-0.25)));
  EXPECT_FLOAT_EQ(m.vx, 0.3F);
  EXPECT_FLOAT_EQ(m.yawspeed, -0.2F);
  EXPECT_EQ(m.reset_counter, 7);
  EXPECT_TRUE(std::isnan(m.velocity_covariance[0]));  // velocity covariance not estimated
}

TEST(PoseMessages, CovarianceSignsFollowTheFlippedAxes) {
  hf::PoseOutput p = pose_at(0, 0, 0);
  auto& c = p.covariance;
  c(0, 0) = 1e-4;
  c(1, 1) = 4e-4;
  c(2, 2) = 1e-2;
  c(0, 1) = c(1, 0) = 2e-5;
  c(0, 2) = c(2, 0) = 3e-5;
  c(1, 2) = c(2, 1) = 5e-5;
  const mav::Odometry m = hf::odometry_message(p, 0, 0);
  EXPECT_FLOAT_EQ(m.pose_covariance[0], 1e-4F);
  EXPECT_FLOAT_EQ(m.pose_covariance[1], -2e-5F);  // x y: y flips
  EXPECT_FLOAT_EQ(m.pose_covariance[5], -3e-5F);  // x yaw: yaw flips
  EXPECT_FLOAT_EQ(m.pose_covariance[6], 4e-4F);
  EXPECT_FLOAT_EQ(m.pose_covariance[10], 5e-5F);  // y yaw: both flip
  EXPECT_FLOAT_EQ(m.pose_covariance[20], 1e-2F);
  EXPECT_FLOAT_EQ(m.pose_covariance[2], 0.0F);  // z rows are not estimated
}

TEST(PoseMessages, QualityFallsWithTheSpreadAndIsMinusOneWhenInvalid) {
  hf::PoseOutput p = pose_at(0, 0, 0);
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, 100);
  p.covariance(0, 0) = p.covariance(1, 1) = 0.05 * 0.05;  // 5 cm
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, 50);
  p.covariance(0, 0) = p.covariance(1, 1) = 0.2 * 0.2;
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, 0);
  p.health = hf::Health::kInvalid;
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, -1);
}

TEST(PoseMessages, HeartbeatStatusFollowsHealthAndTheOverrunAlarm) {
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kNotInitialized, false), mav::kMavStateStandby);
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kNominal, false), mav::kMavStateActive);
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kOdometryOnly, false), mav::kMavStateCritical);
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kVisionOnly, false), mav::kMavStateCritical);
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kInvalid, false), mav::kMavStateEmergency);
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kNominal, true), mav::kMavStateCritical);
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kNotInitialized, true), mav::kMavStateCritical);
  EXPECT_EQ(hf::heartbeat_status(hf::Health::kInvalid, true), mav::kMavStateEmergency);
}

TEST(PoseMessages, HealthTextSaysWhyThePoseIsNotNominal) {
  using C = hf::HealthCause;
  using H = hf::Health;
  struct Case {
    H health;
    C cause;
    const char* text;
    std::uint8_t severity;
  };
  // A cause that does not go with the health is not said (the last two).
  const Case cases[] = {
      {H::kNominal, C::kInputs, "harmoloc: pose nominal", mav::kSeverityInfo},
      {H::kVisionOnly, C::kInputs, "harmoloc: vision only (no encoder data)",
       mav::kSeverityWarning},
      {H::kInvalid, C::kInputs, "harmoloc: pose invalid (no camera, no encoders)",
       mav::kSeverityCritical},
      {H::kInvalid, C::kOffMap, "harmoloc: pose invalid (outside the mapped region)",
       mav::kSeverityCritical},
      {H::kOdometryOnly, C::kHeadingNotCovered, "harmoloc: odometry only (heading not mapped here)",
       mav::kSeverityWarning},
      {H::kInvalid, C::kHeadingNotCovered, "harmoloc: pose invalid (heading not mapped here)",
       mav::kSeverityCritical},
      {H::kOdometryOnly, C::kBoardsDisagree, "harmoloc: odometry only (boards disagree)",
       mav::kSeverityWarning},
      {H::kInvalid, C::kBoardsDisagree, "harmoloc: pose invalid (boards disagree)",
       mav::kSeverityCritical},
      {H::kOdometryOnly, C::kSpreadWide, "harmoloc: odometry only (pose spread too wide)",
       mav::kSeverityWarning},
      {H::kNominal, C::kHeadingNotCovered, "harmoloc: pose nominal", mav::kSeverityInfo},
      {H::kInvalid, C::kSpreadWide, "harmoloc: pose invalid (no camera, no encoders)",
       mav::kSeverityCritical},
      {H::kOdometryOnly, C::kOffMap, "harmoloc: odometry only (no camera fix)",
       mav::kSeverityWarning},
  };
  for (const Case& c : cases) {
    const hf::HealthText t = hf::health_text(c.health, c.cause);
    EXPECT_STREQ(t.text, c.text);
    EXPECT_EQ(t.severity, c.severity) << c.text;
  }
  // STATUSTEXT holds 50 characters.
  for (const C c :
       {C::kInputs, C::kOffMap, C::kHeadingNotCovered, C::kBoardsDisagree, C::kSpreadWide})
    for (int h = 0; h <= 4; ++h)
      EXPECT_LE(std::strlen(hf::health_text(static_cast<H>(h), c).text), 50U);
}

TEST(PoseMessages, QualityUnknownWhereTheMapDoesNotCoverTheHeading) {
  hf::PoseOutput p = pose_at(1.0, 2.0, 0.5);
  p.covariance(0, 0) = p.covariance(1, 1) = 0.01 * 0.01;
  p.health = hf::Health::kOdometryOnly;
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, 90);
  p.cause = hf::HealthCause::kHeadingNotCovered;
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, 0);
  p.cause = hf::HealthCause::kBoardsDisagree;  // the cloud's narrow spread is not its error
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, 0);
  p.health = hf::Health::kInvalid;
  EXPECT_EQ(hf::odometry_message(p, 0, 0).quality, -1);
}

// ---- read back: what harmoloc-monitor decodes ----------------------------------------------

TEST(PoseMessages, OdometryReadsBackInTheMapFrame) {
  hf::PoseOutput p = pose_at(3.25, -1.5, 2.9);
  p.covariance(0, 0) = 0.02 * 0.02;
  p.covariance(1, 1) = 0.04 * 0.04;
  p.health = hf::Health::kVisionOnly;
  mav::Encoder encoder(1, 197);
  mav::FrameBuffer buffer{};
  const std::size_t n =
      encoder.odometry(hf::odometry_message(p, 1'767'225'600'123'456'789, 9), buffer);
  mav::FrameParser parser;
  ASSERT_EQ(parser.push(buffer.data(), n), n);
  mav::RxFrame frame;
  std::size_t work = 1U << 20U;
  ASSERT_TRUE(parser.next(frame, work));
  ASSERT_EQ(frame.msg_id, mav::kMsgOdometry);
  const hf::MapPose m = hf::map_pose(hf::decode_odometry(frame.payload.data()));
  EXPECT_NEAR(m.t_s, 1'767'225'600.123456, 1e-6);
  EXPECT_NEAR(m.x_m, 3.25, 1e-6);
  EXPECT_NEAR(m.y_m, -1.5, 1e-6);  // the map frame again: y flipped back
  EXPECT_NEAR(m.yaw_rad, 2.9, 1e-6);
  EXPECT_NEAR(m.sigma_m, std::sqrt(0.5 * (0.02 * 0.02 + 0.04 * 0.04)), 1e-6);
  EXPECT_EQ(m.reset_counter, 9);
  EXPECT_EQ(m.quality, 68);  // 100 - 1000 x 0.0316
}

TEST(PoseMessages, HealthReadsBackFromItsTextAndHeartbeat) {
  for (const hf::Health h :
       {hf::Health::kNotInitialized, hf::Health::kNominal, hf::Health::kOdometryOnly,
        hf::Health::kVisionOnly, hf::Health::kInvalid}) {
    hf::Health got = hf::Health::kNominal;
    const char* text = hf::health_text(h, hf::HealthCause::kInputs).text;
    ASSERT_TRUE(hf::health_of_text(text, std::strlen(text), got));
    EXPECT_EQ(got, h);
  }
  hf::Health got = hf::Health::kNominal;
  const char* off = hf::health_text(hf::Health::kInvalid, hf::HealthCause::kOffMap).text;
  ASSERT_TRUE(hf::health_of_text(off, 50, got));
  EXPECT_EQ(got, hf::Health::kInvalid);
  const char* uncovered =
      hf::health_text(hf::Health::kOdometryOnly, hf::HealthCause::kHeadingNotCovered).text;
  ASSERT_TRUE(hf::health_of_text(uncovered, 50, got));
  EXPECT_EQ(got, hf::Health::kOdometryOnly);
  const char* disagree =
      hf::health_text(hf::Health::kInvalid, hf::HealthCause::kBoardsDisagree).text;
  ASSERT_TRUE(hf::health_of_text(disagree, 50, got));
  EXPECT_EQ(got, hf::Health::kInvalid);
  EXPECT_FALSE(hf::health_of_text("harmoloc: overrun alarm", 50, got));
  EXPECT_FALSE(hf::health_of_text("harmoloc: pose nominal", 8, got));  // cut short: no match
  EXPECT_TRUE(hf::health_of_heartbeat(mav::kMavStateActive, got));
  EXPECT_EQ(got, hf::Health::kNominal);
  EXPECT_FALSE(hf::health_of_heartbeat(mav::kMavStateCritical, got));
}
