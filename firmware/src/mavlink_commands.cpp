// The link's inbound side of the cycle: the commands a peer may send and what they do. Members
// of LocalizationCycle, kept apart from the cycle's stages. Protocol: docs/wire-protocol.md.
#include "harmoloc/firmware/localization_cycle.hpp"

namespace harmoloc::firmware {

namespace {

// The answer to "relocalize" in COMMAND_ACK.result_param2: where the particles went.
constexpr std::int32_t kRelocalizedAroundFix = 1;
constexpr std::int32_t kRelocalizedOverMap = 2;

}  // namespace

void LocalizationCycle::set_signing_time(std::uint64_t unix_time_us) {
  signer_.set_time(mavlink::signing_timestamp_from_unix_us(unix_time_us), clock_.now_ns());
}

void LocalizationCycle::restore_signing_state(const mavlink::SigningState& state,
                                              hal::PersistentRecord* store,
                                              std::uint64_t durable_high_water) {
  signer_.restore(state);
  signer_.set_durable(durable_high_water);
  signing_store_ = store;
}

void LocalizationCycle::service_link() {
  const std::uint64_t now_ns = clock_.now_ns();
  signer_.advance(now_ns);
  if (signing_store_ != nullptr) {
    // The replay protection's state goes to storage ahead of need: a high-water mark above what
    // may be accepted in the next half minute (or above a frame that is waiting for it).
    signer_.set_durable(signing_store_->durable_tag());
    if (signer_.persist_due(now_ns)) {
      const mavlink::SigningState state = signer_.snapshot(now_ns);
      const std::size_t n =
          mavlink::format_signing_state(state, signing_record_.data(), signing_record_.size());
      if (n > 0 &&
          !signing_store_->offer(reinterpret_cast<const std::uint8_t*>(signing_record_.data()), n,
                                 state.high_water))
        signer_.snapshot_refused();
    }
  }
  receiver_.begin_cycle();
  reseed_ = Reseed{};
  mavlink::CommandLong command;
  while (receiver_.next_command(link_, command)) {
    mavlink::CommandAck ack;
    ack.command = command.command;
    ack.target_system = command.source_system;
    ack.target_component = command.source_component;
    ack.result = execute(command, ack.result_param2);
    receiver_.count_result(ack.result);
    send(mavlink_.command_ack(ack, frame_buffer_));
  }
  // TIMESYNC: our time on the clock ODOMETRY's time_usec is on (the data clock: the monotonic
  // clock on a live board, the recording's time in a replay), so that the peer can map one to
  // its own clock.
  mavlink::TimesyncRequest request;
  if (receiver_.take_timesync(request)) {
    const std::uint64_t ours_ns = live_clock_ ? now_ns : data_time_ns_;
    send(mavlink_.timesync(mavlink::Timesync{static_cast<std::int64_t>(ours_ns), request.ts1,
                                             request.system_id, request.component_id},
                           frame_buffer_));
  }
  if (reseed_.kind == Reseed::Kind::kNone) return;
  if (reseed_.kind == Reseed::Kind::kAround) {
    filter_.initialize(reseed_.centre, reseed_.position_sigma_m, reseed_.yaw_sigma_rad,
                       reseed_.uniform_yaw);
  } else {
    const algorithms::HarmonicModel& m = map_.model;
    filter_.initialize_around_points(m.target_x_m.data(), m.target_y_m.data(), m.sample_count,
                                     reseed_.position_sigma_m);
  }
  kidnap_.reset();  // the new cloud's first match is not to be compared with the old one's
  ++reset_counter_;
  // This cycle's outputs (ODOMETRY, trajectory) show the new cloud at once.
  const algorithms::PoseEstimate e = filter_.estimate();
  pose_.pose = e.mean;
  pose_.covariance = e.covariance;
  pose_.valid = true;
  set_published_health();
}

mavlink::MavResult LocalizationCycle::execute(const mavlink::CommandLong& command,
                                              std::int32_t& result_param2) {
  switch (command.command) {
    case mavlink::kCmdRelocalize:
      return relocalize(result_param2);
    case mavlink::kCmdSetPose:
      return set_pose(command);
    case mavlink::kCmdRequestMessage:
      return request_message(command);
    default:
      return mavlink::MavResult::kUnsupported;
  }
}

mavlink::MavResult LocalizationCycle::relocalize(std::int32_t& how) {
  const double sigma_m = init_sigma_m_;
  if (ever_fix_ && camera_fresh(last_fix_ns_)) {
    // The camera sees a trained place now: that fix is a global position (Yang et al.'s recovery,
    // with the harmonic localizer as the global guess). The heading is the training run's there
    // when the map knows it (on a floor, the one the boards' bearings give), else unknown.
    const SeedHeading h = seed_heading(last_known_fix_.x_m, last_known_fix_.y_m);
    reseed_ = Reseed{Reseed::Kind::kAround,
                     algorithms::Pose2{last_known_fix_.x_m, last_known_fix_.y_m, h.yaw_rad},
                     sigma_m, h.sigma_rad, h.uniform};
    how = kRelocalizedAroundFix;
  } else {
    // No trusted fix: the robot is somewhere on the trained route, nothing more is known.
    if (map_.model.sample_count == 0) return mavlink::MavResult::kFailed;
    reseed_ = Reseed{Reseed::Kind::kOverMap, algorithms::Pose2{}, sigma_m, 0.0, true};
    how = kRelocalizedOverMap;
  }
  return mavlink::MavResult::kAccepted;
}

mavlink::MavResult LocalizationCycle::set_pose(const mavlink::CommandLong& command) {
  mavlink::SetPoseRequest r;
  const mavlink::MavResult checked = mavlink::read_set_pose(command, init_sigma_m_, r);
  if (checked != mavlink::MavResult::kAccepted) return checked;
  reseed_ = Reseed{Reseed::Kind::kAround, algorithms::Pose2{r.x_m, r.y_m, r.yaw_rad},
                   r.position_sigma_m, r.yaw_sigma_rad, false};
  return mavlink::MavResult::kAccepted;
}

mavlink::MavResult LocalizationCycle::request_message(const mavlink::CommandLong& command) {
  std::uint32_t id = 0;
  if (mavlink::read_request_message(command, id) != mavlink::MavResult::kAccepted)
    return mavlink::MavResult::kDenied;
  switch (id) {
    case mavlink::kMsgHeartbeat:
      heartbeat_requested_ = true;  // sent by this cycle's publish, after the ACK
      return mavlink::MavResult::kAccepted;
    case mavlink::kMsgOdometry:
      // Every cycle sends one once a pose exists (or a re-seed asked for earlier in this cycle
      // makes one); this cycle's follows the ACKs.
      return filter_.initialized() || reseed_.kind != Reseed::Kind::kNone
                 ? mavlink::MavResult::kAccepted
                 : mavlink::MavResult::kFailed;
    default:
      return mavlink::MavResult::kDenied;
  }
}

}  // namespace harmoloc::firmware
