// The publish stage: HEARTBEAT on schedule, the pose, health changes and capture-to-send
// latency on the link.
#include "harmoloc/firmware/localization_cycle.hpp"

#include <cmath>

namespace harmoloc::firmware {

void LocalizationCycle::send(std::size_t size) {
  if (link_.write_frame(frame_buffer_.data(), size) != hal::LinkWrite::kSent)
    ++counters_.link_dropped;
}

void LocalizationCycle::report_capture_to_send() {
  const LatencyWindow::Summary s = capture_to_send_window_.take();
  if (s.count == 0) return;  // a replay, or no pose sent since the last heartbeat
  // time_boot_ms: the data clock, which on a live board is the monotonic clock (time since boot).
  const auto boot_ms = static_cast<std::uint32_t>(data_time_ns_ / 1'000'000U);
  send(mavlink_.named_value_float(boot_ms, "c2s_p50_ms",
                                  static_cast<float>(static_cast<double>(s.median_ns) * 1e-6),
                                  frame_buffer_));
  send(mavlink_.named_value_float(boot_ms, "c2s_max_ms",
                                  static_cast<float>(static_cast<double>(s.max_ns) * 1e-6),
                                  frame_buffer_));
}

void LocalizationCycle::publish() {
  const Health health = pose_.health;
  const bool heartbeat_due = data_time_ns_ >= next_heartbeat_ns_;
  if (heartbeat_due || heartbeat_requested_) {
    heartbeat_requested_ = false;
    mavlink::Heartbeat hb;
    hb.system_status = heartbeat_status(health, overrun_alarm_);
    send(mavlink_.heartbeat(hb, frame_buffer_));
  }
  if (heartbeat_due) {  // a requested one leaves the schedule alone
    report_capture_to_send();
    const auto step = static_cast<std::uint64_t>(std::llround(1e9 / config_.link.heartbeat_hz));
    next_heartbeat_ns_ = (next_heartbeat_ns_ == 0 ? data_time_ns_ : next_heartbeat_ns_) + step;
    if (next_heartbeat_ns_ <= data_time_ns_) next_heartbeat_ns_ = data_time_ns_ + step;
  }
  // Invalid because the pose is off the map, and odometry only because the map does not cover
  // the heading, say so in their own words.
  const HealthCause cause = pose_.valid ? pose_.cause : HealthCause::kInputs;
  if (cause == HealthCause::kOffMap) ++counters_.off_map_cycles;
  if (health != last_reported_health_ || cause != last_reported_cause_) {
    const HealthText t = health_text(health, cause);
    send(mavlink_.statustext(t.severity, t.text, frame_buffer_));
    last_reported_health_ = health;
    last_reported_cause_ = cause;
  }
  if (pending_overrun_text_ != nullptr) {
    send(mavlink_.statustext(overrun_alarm_ ? mavlink::kSeverityWarning : mavlink::kSeverityInfo,
                             pending_overrun_text_, frame_buffer_));
    pending_overrun_text_ = nullptr;
  }
  if (pending_text_ != nullptr) {
    send(mavlink_.statustext(mavlink::kSeverityWarning, pending_text_, frame_buffer_));
    pending_text_ = nullptr;
  }
  if (!pose_.valid) return;

  // Map frame -> MAV_FRAME_LOCAL_FRD (pose_messages.hpp).
  send(mavlink_.odometry(odometry_message(pose_, data_time_ns_, reset_counter_), frame_buffer_));
  if (live_clock_ && frame_this_cycle_) {
    const std::uint64_t sent_ns = clock_.now_ns();
    const std::uint64_t latency_ns = sent_ns > frame_time_ns_ ? sent_ns - frame_time_ns_ : 0;
    capture_to_send_.record(latency_ns);
    capture_to_send_window_.record(latency_ns);
  }
}

}  // namespace harmoloc::firmware
