#pragma once
/// @file systemd's service notifications (the sd_notify(3) protocol) for the packaged service
/// (Type=notify, WatchdogSec): READY=1 once start-up has checked everything, WATCHDOG=1 from
/// the run loop, STATUS= lines that `systemctl status` shows, STOPPING=1 at the end.
///
/// Written here rather than with libsystemd's sd_notify() because the run loop may not block or
/// allocate: sd_notify() opens, connects and closes a socket on every call, while this opens
/// one datagram socket at start-up and sends with MSG_DONTWAIT (a full queue drops the message
/// and counts it; systemd then sees a late watchdog, which is what it is for). Without
/// NOTIFY_SOCKET (not started by systemd, or Type=exec) every call does nothing.

#include <cstddef>
#include <cstdint>
#include <string>

namespace harmoloc::drivers {

class ServiceNotifier {
 public:
  ServiceNotifier() = default;
  ServiceNotifier(const ServiceNotifier&) = delete;
  ServiceNotifier& operator=(const ServiceNotifier&) = delete;
  ~ServiceNotifier();

  /// Reads NOTIFY_SOCKET (a path, or @name for the abstract namespace), WATCHDOG_USEC and
  /// WATCHDOG_PID (the watchdog is ours only if it names this process) and connects. Returns ""
  /// (also without NOTIFY_SOCKET) or one line saying what is wrong with them.
  std::string open();

  bool active() const { return fd_ >= 0; }
  /// The watchdog interval systemd asked for (WatchdogSec), 0 without a watchdog.
  std::uint64_t watchdog_interval_ns() const { return watchdog_ns_; }

  /// READY=1 with a STATUS= line.
  void ready(const char* status);
  /// A STATUS= line (at most 200 characters are sent).
  void status(const char* text);
  /// STOPPING=1 with a STATUS= line.
  void stopping(const char* status);
  /// WATCHDOG=1 when half the watchdog interval has passed since the last one: call every cycle.
  void feed(std::uint64_t now_ns);

  std::uint64_t sent() const { return sent_; }
  std::uint64_t failed() const { return failed_; }

 private:
  void send(const char* message, std::size_t length);
  void send_with_status(const char* head, const char* status);

  int fd_ = -1;
  std::uint64_t watchdog_ns_ = 0;
  std::uint64_t last_feed_ns_ = 0;
  bool fed_ = false;
  std::uint64_t sent_ = 0, failed_ = 0;
};

}  // namespace harmoloc::drivers
