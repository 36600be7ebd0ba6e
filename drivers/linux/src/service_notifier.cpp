#include "harmoloc/drivers/service_notifier.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace harmoloc::drivers {

ServiceNotifier::~ServiceNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

std::string ServiceNotifier::open() {
  const char* socket_name = std::getenv("NOTIFY_SOCKET");
  if (socket_name == nullptr || socket_name[0] == '\0') return "";
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::size_t length = std::strlen(socket_name);
  if ((socket_name[0] != '/' && socket_name[0] != '@') || length >= sizeof address.sun_path)
    return std::string("NOTIFY_SOCKET=") + socket_name + ": not a socket path or @name";
  std::memcpy(address.sun_path, socket_name, length);
  if (socket_name[0] == '@') address.sun_path[0] = '\0';  // the abstract namespace
  const auto address_length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + length);

  const char* usec = std::getenv("WATCHDOG_USEC");
  if (usec != nullptr && usec[0] != '\0') {
    const char* pid = std::getenv("WATCHDOG_PID");
    char* end = nullptr;
    errno = 0;
    const unsigned long long us = std::strtoull(usec, &end, 10);
    if (errno != 0 || *end != '\0' || us == 0)
      return std::string("WATCHDOG_USEC=") + usec + ": not a number of microseconds";
    const bool ours = pid == nullptr || pid[0] == '\0' ||
                      std::strtoll(pid, nullptr, 10) == static_cast<long long>(::getpid());
    if (ours) watchdog_ns_ = static_cast<std::uint64_t>(us) * 1000U;
  }

  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return std::string("notify socket: ") + std::strerror(errno);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), address_length) != 0) {
    const int e = errno;
    ::close(fd);
    return std::string("NOTIFY_SOCKET=") + socket_name + ": " + std::strerror(e);
  }
  fd_ = fd;
  return "";
}

void ServiceNotifier::send(const char* message, std::size_t length) {
  if (fd_ < 0) return;
  if (::send(fd_, message, length, MSG_DONTWAIT | MSG_NOSIGNAL) == static_cast<ssize_t>(length))
    ++sent_;
  else
    ++failed_;
}

void ServiceNotifier::send_with_status(const char* head, const char* status) {
  if (fd_ < 0) return;
  char message[256];
  const int n = std::snprintf(message, sizeof message, "%sSTATUS=%.200s", head, status);
  if (n > 0) send(message, std::strlen(message));
}

void ServiceNotifier::ready(const char* status) {
  send_with_status("READY=1\n", status);
}

void ServiceNotifier::status(const char* text) {
  send_with_status("", text);
}

void ServiceNotifier::stopping(const char* status) {
  send_with_status("STOPPING=1\n", status);
}

void ServiceNotifier::feed(std::uint64_t now_ns) {
  if (fd_ < 0 || watchdog_ns_ == 0) return;
  if (fed_ && now_ns - last_feed_ns_ < watchdog_ns_ / 2) return;
  static constexpr char kWatchdog[] = "WATCHDOG=1";
  send(kWatchdog, sizeof kWatchdog - 1);
  last_feed_ns_ = now_ns;
  fed_ = true;
}

}  // namespace harmoloc::drivers
