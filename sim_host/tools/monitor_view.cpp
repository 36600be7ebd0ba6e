// harmoloc-monitor's view: the names it prints and the screen it draws.
#include <cstdio>
#include <cstring>
#include <string>

#include "monitor_parts.hpp"

namespace monitor_detail {

const char* result_name(std::uint8_t r) {
  static const char* kNames[] = {"ACCEPTED", "TEMPORARILY_REJECTED", "DENIED", "UNSUPPORTED",
                                 "FAILED"};
  return r < 5 ? kNames[r] : "OTHER";
}

const char* command_name(std::uint16_t c) {
  switch (c) {
    case mv::kCmdRelocalize:
      return "relocalize";
    case mv::kCmdSetPose:
      return "set pose";
    case mv::kCmdRequestMessage:
      return "request message";
    default:
      return "command";
  }
}

// NAMED_VALUE_FLOAT: time_boot_ms (4), value (4), name (10, not terminated when full).
void take_named_value(const mv::RxFrame& frame, View& v) {
  float value = 0.0F;
  std::memcpy(&value, frame.payload.data() + 4, sizeof value);
  const char* name = reinterpret_cast<const char*>(frame.payload.data() + 8);
  const std::string key(name, ::strnlen(name, mv::kNamedValueNameBytes));
  if (key == "c2s_p50_ms") v.latency_p50_ms = value;
  if (key == "c2s_max_ms") v.latency_max_ms = value;
}

namespace {

double odometry_rate_hz(const View& v) {
  if (!v.pose || v.odometry < 2 || !(v.pose->t_s > v.first_t_s)) return 0.0;
  return static_cast<double>(v.odometry - 1) / (v.pose->t_s - v.first_t_s);
}

}  // namespace

std::string health_text_of(const View& v) {
  if (v.health) return firmware::health_name(*v.health);
  if (v.heartbeat_status && *v.heartbeat_status == mv::kMavStateCritical) return "degraded";
  return "unknown";
}

void draw(const View& v, const mv::ParserCounters& p, const std::string& source, bool clear) {
  std::string out = clear ? "\x1b[H\x1b[J" : "";
  char line[256];
  std::snprintf(line, sizeof line, "harmoloc-monitor: %s\n", source.c_str());
  out += line;
  if (v.pose) {
    const firmware::MapPose& m = *v.pose;
    std::snprintf(line, sizeof line,
                  "pose     t %.3f s  x %.3f m  y %.3f m  yaw %.1f deg (map frame)\n", m.t_s, m.x_m,
                  m.y_m, m.yaw_rad * 57.29577951308232);
    out += line;
    std::snprintf(line, sizeof line, "spread   %.1f cm  quality %d  resets %u\n", m.sigma_m * 100.0,
                  m.quality, unsigned{m.reset_counter});
    out += line;
  } else {
    out += "pose     none yet\n";
  }
  std::snprintf(line, sizeof line, "health   %s\n", health_text_of(v).c_str());
  out += line;
  if (v.latency_p50_ms && v.latency_max_ms) {
    std::snprintf(line, sizeof line,
                  "latency  capture to send %.1f ms median, %.1f ms max (last second)\n",
                  *v.latency_p50_ms, *v.latency_max_ms);
    out += line;
  }
  std::snprintf(line, sizeof line, "status   %s\n",
                v.last_text.empty() ? "-" : v.last_text.c_str());
  out += line;
  std::snprintf(line, sizeof line,
                "messages %llu frames: %llu ODOMETRY (%.1f Hz of data time), %llu HEARTBEAT, %llu "
                "STATUSTEXT, "
                "%llu COMMAND_ACK, %llu other\n",
                static_cast<unsigned long long>(v.frames),
                static_cast<unsigned long long>(v.odometry), odometry_rate_hz(v),
                static_cast<unsigned long long>(v.heartbeats),
                static_cast<unsigned long long>(v.texts), static_cast<unsigned long long>(v.acks),
                static_cast<unsigned long long>(v.other));
  out += line;
  std::snprintf(
      line, sizeof line,
      "link     %llu bytes, %llu CRC errors, %llu bytes of garbage; signed %llu ok, %llu "
      "bad, %llu unsigned\n",
      static_cast<unsigned long long>(p.bytes), static_cast<unsigned long long>(p.crc_errors),
      static_cast<unsigned long long>(p.garbage_bytes),
      static_cast<unsigned long long>(v.signed_ok), static_cast<unsigned long long>(v.signed_bad),
      static_cast<unsigned long long>(v.unsigned_frames));
  out += line;
  std::fputs(out.c_str(), stdout);
  std::fflush(stdout);
}

}  // namespace monitor_detail
