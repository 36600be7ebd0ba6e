#include "health_log.hpp"

#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace harmoloc::boards {

namespace {

constexpr std::uint64_t kMinInterval_ns = 1'000'000'000;

// sd-daemon(3) priorities: what a user filtering the journal with -p should see.
int priority_of(firmware::Health health) {
  switch (health) {
    case firmware::Health::kNominal:
      return 5;  // notice
    case firmware::Health::kOdometryOnly:
    case firmware::Health::kVisionOnly:
      return 4;  // warning
    case firmware::Health::kInvalid:
      return 3;  // err
    case firmware::Health::kNotInitialized:
      break;
  }
  return 6;  // info
}

}  // namespace

void HealthLog::start() {
  struct stat st {};
  if (::fstat(STDERR_FILENO, &st) != 0) return;
  socket_ = S_ISSOCK(st.st_mode);
  // JOURNAL_STREAM is "device:inode" of the stream systemd connected; it is inherited by
  // children whose stderr is something else, so it counts only if it is stderr itself.
  if (const char* js = std::getenv("JOURNAL_STREAM"); js != nullptr) {
    unsigned long long dev = 0, ino = 0;
    if (std::sscanf(js, "%llu:%llu", &dev, &ino) == 2)
      journal_ = dev == static_cast<unsigned long long>(st.st_dev) &&
                 ino == static_cast<unsigned long long>(st.st_ino);
  }
}

void HealthLog::write(int priority, const char* text) {
  char out[sizeof line_ + 8];
  const int n = journal_ ? std::snprintf(out, sizeof out, "<%d>%s\n", priority, text)
                         : std::snprintf(out, sizeof out, "%s\n", text);
  if (n <= 0) return;
  const auto length = std::strlen(out);
  const ssize_t written = socket_ ? ::send(STDERR_FILENO, out, length, MSG_DONTWAIT | MSG_NOSIGNAL)
                                  : ::write(STDERR_FILENO, out, length);
  if (written == static_cast<ssize_t>(length))
    ++lines_;
  else
    ++lost_;
}

const char* HealthLog::observe(firmware::Health health, bool overrun_alarm, std::uint64_t now_ns) {
  if (health != last_health_) ++changes_since_line_;
  last_health_ = health;
  const char* said = nullptr;
  if (overrun_alarm != logged_alarm_) {
    // Rare by construction (the alarm needs a streak of cycles to change), said at once.
    logged_alarm_ = overrun_alarm;
    std::snprintf(
        line_, sizeof line_, "harmoloc: %s",
        overrun_alarm ? "cycle overrun: the cycle is over its budget" : "cycle overrun cleared");
    write(overrun_alarm ? 4 : 5, line_);
    said = line_;
  }
  const bool changed = health != logged_health_;
  if (!changed || (started_ && now_ns - last_line_ns_ < kMinInterval_ns)) return said;
  // Flapping in between: said with the count, once the second is up.
  const std::uint64_t between = changes_since_line_ > 1 ? changes_since_line_ - 1 : 0;
  if (between > 0)
    std::snprintf(line_, sizeof line_, "harmoloc: health %s (was %s; %llu changes in between)",
                  firmware::health_name(health), firmware::health_name(logged_health_),
                  static_cast<unsigned long long>(between));
  else
    std::snprintf(line_, sizeof line_, "harmoloc: health %s (was %s)",
                  firmware::health_name(health), firmware::health_name(logged_health_));
  write(priority_of(health), line_);
  logged_health_ = health;
  last_line_ns_ = now_ns;
  started_ = true;
  changes_since_line_ = 0;
  return line_;
}

}  // namespace harmoloc::boards
