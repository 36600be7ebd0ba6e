#pragma once
/// @file What the pieces of harmoloc-monitor (harmoloc_monitor.cpp, monitor_view.cpp) share: what
/// the stream said so far and how it is shown. Private to sim_host/tools.

#include <cstdint>
#include <optional>
#include <string>

#include "harmoloc/firmware/mavlink_inbound.hpp"
#include "harmoloc/firmware/mavlink_parser.hpp"
#include "harmoloc/firmware/mavlink_v2.hpp"
#include "harmoloc/firmware/pose_messages.hpp"

namespace monitor_detail {

using namespace harmoloc;
namespace mv = firmware::mavlink;

// What the stream said so far.
struct View {
  std::optional<firmware::MapPose> pose;
  std::optional<firmware::Health> health;
  std::optional<std::uint8_t> heartbeat_status;
  std::string last_text;
  std::uint64_t frames = 0, odometry = 0, heartbeats = 0, texts = 0, acks = 0, other = 0;
  std::uint64_t signed_ok = 0, signed_bad = 0, unsigned_frames = 0;
  double first_t_s = 0.0;  // ODOMETRY's time of the first one seen: the rate is over data time
  // Capture to send over the last heartbeat period (NAMED_VALUE_FLOAT c2s_p50_ms, c2s_max_ms;
  // live boards only).
  std::optional<double> latency_p50_ms, latency_max_ms;
};

// monitor_view.cpp
const char* result_name(std::uint8_t r);
const char* command_name(std::uint16_t c);
void take_named_value(const mv::RxFrame& frame, View& v);
std::string health_text_of(const View& v);
void draw(const View& v, const mv::ParserCounters& p, const std::string& source, bool clear);

}  // namespace monitor_detail
