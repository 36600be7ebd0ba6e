#pragma once
/// @file Health changes and overrun alarms as lines on stderr, which the packaged service sends
/// to the journal: with the journal's priority prefix (`<4>` and so on, sd-daemon(3)) when
/// stderr is the journal's stream (JOURNAL_STREAM), so that `journalctl -p warning` shows
/// them. A health that flaps from cycle to cycle is said at most once a second, with the number
/// of changes in between. The line is formatted in a buffer of its own and written without
/// blocking (a journal that does not keep up loses the line, counted), so the run loop can call
/// it every cycle.

#include <cstdint>

#include "harmoloc/firmware/pose_output.hpp"

namespace harmoloc::boards {

class HealthLog {
 public:
  /// Reads JOURNAL_STREAM and what stderr is. Call once at start-up.
  void start();

  /// After every cycle: the published health and the overrun alarm. Returns the line it wrote
  /// (for the service's STATUS=), or nullptr when it wrote none.
  const char* observe(firmware::Health health, bool overrun_alarm, std::uint64_t now_ns);

  std::uint64_t lines() const { return lines_; }
  std::uint64_t lost() const { return lost_; }

 private:
  void write(int priority, const char* text);

  bool journal_ = false;  // stderr is the journal's stream: prefix the priority
  bool socket_ = false;   // stderr is a socket: send without blocking
  bool started_ = false;
  firmware::Health logged_health_ = firmware::Health::kNotInitialized;
  bool logged_alarm_ = false;
  std::uint64_t last_line_ns_ = 0;
  std::uint64_t changes_since_line_ = 0;
  firmware::Health last_health_ = firmware::Health::kNotInitialized;
  std::uint64_t lines_ = 0, lost_ = 0;
  char line_[160] = {};
};

}  // namespace harmoloc::boards
