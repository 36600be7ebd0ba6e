#include "harmoloc/firmware/mavlink_inbound.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "harmoloc/algorithms/geometry.hpp"

namespace harmoloc::firmware::mavlink {

CommandLong decode_command_long(const RxFrame& frame) {
  // Wire order: seven floats, command (uint16), target system, target component, confirmation.
  const std::uint8_t* p = frame.payload.data();
  CommandLong c;
  for (std::size_t i = 0; i < c.param.size(); ++i) {
    const std::uint32_t u = static_cast<std::uint32_t>(p[4 * i]) |
                            static_cast<std::uint32_t>(p[4 * i + 1]) << 8U |
                            static_cast<std::uint32_t>(p[4 * i + 2]) << 16U |
                            static_cast<std::uint32_t>(p[4 * i + 3]) << 24U;
    std::memcpy(&c.param[i], &u, 4);
  }
  c.command = static_cast<std::uint16_t>(p[28] | (p[29] << 8U));
  c.target_system = p[30];
  c.target_component = p[31];
  c.confirmation = p[32];
  c.source_system = frame.system_id;
  c.source_component = frame.component_id;
  return c;
}

Timesync decode_timesync(const RxFrame& frame) {
  const std::uint8_t* p = frame.payload.data();
  const auto i64 = [p](std::size_t at) {
    std::uint64_t u = 0;
    for (std::size_t i = 0; i < 8; ++i) u |= static_cast<std::uint64_t>(p[at + i]) << (8U * i);
    return static_cast<std::int64_t>(u);
  };
  Timesync t;
  t.tc1 = i64(0);
  t.ts1 = i64(8);
  t.target_system = p[16];
  t.target_component = p[17];
  return t;
}

MavResult read_set_pose(const CommandLong& command, double default_position_sigma_m,
                        SetPoseRequest& out) {
  const double x = command.param[0];
  const double y_frd = command.param[1];
  const double yaw_frd = command.param[2];
  if (!std::isfinite(x) || !std::isfinite(y_frd) || !std::isfinite(yaw_frd) ||
      std::fabs(x) > kMaxSetPoseCoordinateM || std::fabs(y_frd) > kMaxSetPoseCoordinateM) {
    return MavResult::kDenied;
  }
  double sigma_m = command.param[3];
  double sigma_yaw = command.param[4];
  if (std::isnan(sigma_m) || sigma_m == 0.0) sigma_m = default_position_sigma_m;
  if (std::isnan(sigma_yaw) || sigma_yaw == 0.0) sigma_yaw = kDefaultSetPoseYawSigmaRad;
  if (!(sigma_m > 0.0 && sigma_m <= kMaxSetPosePositionSigmaM) ||
      !(sigma_yaw > 0.0 && sigma_yaw <= algorithms::kPi)) {
    return MavResult::kDenied;
  }
  // LOCAL_FRD (z down) -> map frame (z up): y and yaw change sign.
  out.x_m = x;
  out.y_m = -y_frd;
  out.yaw_rad = algorithms::wrap_angle_rad(-yaw_frd);
  out.position_sigma_m = sigma_m;
  out.yaw_sigma_rad = sigma_yaw;
  return MavResult::kAccepted;
}

MavResult read_request_message(const CommandLong& command, std::uint32_t& msg_id) {
  const float id = command.param[0];
  if (!(id >= 0.0F && id <= 16777215.0F) || id != std::floor(id)) return MavResult::kDenied;
  msg_id = static_cast<std::uint32_t>(id);
  return MavResult::kAccepted;
}

CommandReceiver::CommandReceiver(const LinkConfig& link, Signer* signer)
    : system_id_(link.system_id), component_id_(link.component_id), signer_(signer) {
  for (const std::uint8_t id : link.accept_system_ids) accept_systems_.set(id);
  for (const std::uint8_t id : link.accept_component_ids) accept_components_.set(id);
}

void CommandReceiver::begin_cycle() {
  if (got_bytes_ || parser_.buffered() == 0) {
    idle_cycles_ = 0;
  } else if (idle_cycles_ < kStallCycles) {
    ++idle_cycles_;
  }
  bytes_this_cycle_ = frames_this_cycle_ = commands_this_cycle_ = 0;
  work_ = kWorkPerCycle;
  got_bytes_ = saturated_ = false;
}

bool CommandReceiver::next_command(hal::PoseLink& link, CommandLong& out) {
  while (frames_this_cycle_ < kMaxFramesPerCycle && commands_this_cycle_ < kMaxCommandsPerCycle) {
    if (parser_.next(frame_, work_)) {
      ++frames_this_cycle_;
      if (admit(frame_, out)) {
        ++commands_this_cycle_;
        return true;
      }
      continue;
    }
    if (work_ == 0) break;
    std::size_t room = 0;
    std::uint8_t* to = parser_.write_area(room);
    room = std::min(room, kMaxBytesPerCycle - bytes_this_cycle_);
    const std::size_t n = room > 0 ? link.read_bytes(to, room) : 0U;
    if (n > 0) {
      parser_.commit(n);
      bytes_this_cycle_ += n;
      got_bytes_ = true;
      continue;
    }
    if (room == 0) break;  // limit reached with bytes still waiting
    // Nothing more on the line: a partial candidate that has waited too long is a false start.
    if (idle_cycles_ >= kStallCycles && parser_.buffered() > 0) {
      parser_.skip_candidate();
      --work_;
      continue;
    }
    return false;
  }
  if (!saturated_) ++counters_.saturated_cycles;
  saturated_ = true;
  return false;
}

bool CommandReceiver::admit(const RxFrame& frame, CommandLong& out) {
  if (frame.msg_id == kMsgTimesync) {
    note_timesync(frame);
    return false;
  }
  if (frame.msg_id != kMsgCommandLong) {
    ++counters_.ignored_messages;
    return false;
  }
  out = decode_command_long(frame);
  // Component 0 addresses every component of a system.
  if (out.target_system != system_id_ ||
      (out.target_component != component_id_ && out.target_component != 0)) {
    ++counters_.ignored_messages;
    return false;
  }
  if (!accept_systems_.test(frame.system_id) || !accept_components_.test(frame.component_id)) {
    ++counters_.rejected_source;
    return false;
  }
  return signature_ok(frame);
}

void CommandReceiver::note_timesync(const RxFrame& frame) {
  const Timesync t = decode_timesync(frame);
  // tc1 != 0: an answer to someone's request, not a request. Target 0 (or a sender without the
  // extension fields) addresses every system or component.
  if (t.tc1 != 0 || (t.target_system != 0 && t.target_system != system_id_) ||
      (t.target_component != 0 && t.target_component != component_id_)) {
    ++counters_.ignored_messages;
    return;
  }
  if (!signature_ok(frame)) return;
  timesync_ = TimesyncRequest{t.ts1, frame.system_id, frame.component_id};
  timesync_pending_ = true;
  ++counters_.timesync_requests;
}

bool CommandReceiver::signature_ok(const RxFrame& frame) {
  if (signer_ == nullptr || !signer_->enabled()) return true;
  switch (signer_->verify(frame.bytes, frame.size)) {
    case SignatureCheck::kAccepted:
      return true;
    case SignatureCheck::kUnsigned:
      ++counters_.rejected_unsigned;
      return false;
    case SignatureCheck::kBadSignature:
      ++counters_.rejected_bad_signature;
      return false;
    case SignatureCheck::kReplay:
      ++counters_.rejected_replay;
      return false;
    case SignatureCheck::kTooFarAhead:
      ++counters_.rejected_future;
      return false;
  }
  return false;
}

bool CommandReceiver::take_timesync(TimesyncRequest& out) {
  if (!timesync_pending_) return false;
  out = timesync_;
  timesync_pending_ = false;
  return true;
}

void CommandReceiver::count_result(MavResult result) {
  if (result == MavResult::kAccepted)
    ++counters_.commands_accepted;
  else
    ++counters_.commands_refused;
}

InboundCounters CommandReceiver::counters() const {
  InboundCounters c = counters_;
  const ParserCounters& p = parser_.counters();
  c.bytes_in = p.bytes;
  c.frames_in = p.frames;
  c.crc_errors = p.crc_errors;
  c.bad_headers = p.bad_headers;
  c.garbage_bytes = p.garbage_bytes;
  return c;
}

}  // namespace harmoloc::firmware::mavlink
