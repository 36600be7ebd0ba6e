// The sd_notify protocol as systemd receives it: a datagram socket the test binds, named in
// NOTIFY_SOCKET, as the service manager does for Type=notify.

#include "harmoloc/drivers/service_notifier.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>

namespace hd = harmoloc::drivers;

namespace {

// A socket path short enough for sun_path (108 bytes; the test's temporary folders are longer),
// unique to the process and the call, removed at the end.
class SocketPath {
 public:
  SocketPath() {
    static int next = 0;
    path_ = "/tmp/harmoloc-notify-" + std::to_string(::getpid()) + "-" + std::to_string(next++);
    ::unlink(path_.c_str());
  }
  ~SocketPath() { ::unlink(path_.c_str()); }
  const std::string& str() const { return path_; }

 private:
  std::string path_;
};

// A bound datagram socket standing in for systemd, and the environment it sets; both undone at
// the end.
class FakeServiceManager {
 public:
  explicit FakeServiceManager(const std::string& path_or_name) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::memcpy(a.sun_path, path_or_name.data(), path_or_name.size());
    if (path_or_name[0] == '@') a.sun_path[0] = '\0';
    bound_ =
        ::bind(fd_, reinterpret_cast<const sockaddr*>(&a),
               static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path_or_name.size())) == 0;
    ::setenv("NOTIFY_SOCKET", path_or_name.c_str(), 1);
  }
  ~FakeServiceManager() {
    ::close(fd_);
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
    ::unsetenv("WATCHDOG_PID");
  }
  bool bound() const { return bound_; }
  // The next message, or "" when none is queued.
  std::string receive() {
    char buf[512];
    const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  int fd_ = -1;
  bool bound_ = false;
};

}  // namespace

TEST(ServiceNotifier, WithoutNotifySocketEveryCallDoesNothing) {
  ::unsetenv("NOTIFY_SOCKET");
  hd::ServiceNotifier n;
  EXPECT_EQ(n.open(), "");
  EXPECT_FALSE(n.active());
  n.ready("x");
  n.feed(0);
  n.stopping("y");
  EXPECT_EQ(n.sent() + n.failed(), 0U);
}

TEST(ServiceNotifier, ReadyStatusWatchdogAndStoppingAsSystemdReadsThem) {
  SocketPath path;
  FakeServiceManager manager(path.str());
  ASSERT_TRUE(manager.bound());
  ::setenv("WATCHDOG_USEC", "2000000", 1);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  hd::ServiceNotifier n;
  ASSERT_EQ(n.open(), "");
  ASSERT_TRUE(n.active());
  EXPECT_EQ(n.watchdog_interval_ns(), 2000000000U);

  n.ready("health nominal");
  EXPECT_EQ(manager.receive(), "READY=1\nSTATUS=health nominal");
  // The watchdog: at once, then not before half the interval has passed.
  n.feed(5'000'000'000);
  EXPECT_EQ(manager.receive(), "WATCHDOG=1");
  n.feed(5'999'999'999);
  EXPECT_EQ(manager.receive(), "");
  n.feed(6'000'000'000);
  EXPECT_EQ(manager.receive(), "WATCHDOG=1");
  n.status(std::string(300, 'a').c_str());  // cut at 200 characters
  EXPECT_EQ(manager.receive(), "STATUS=" + std::string(200, 'a'));
  n.stopping("stopped by SIGTERM");
  EXPECT_EQ(manager.receive(), "STOPPING=1\nSTATUS=stopped by SIGTERM");
  EXPECT_EQ(n.sent(), 5U);
  EXPECT_EQ(n.failed(), 0U);
}

TEST(ServiceNotifier, AbstractSocketAndAWatchdogForAnotherProcess) {
  const std::string name = "@harmoloc-notify-test-" + std::to_string(::getpid());
  FakeServiceManager manager(name);
  ASSERT_TRUE(manager.bound());
  ::setenv("WATCHDOG_USEC", "1000000", 1);
  ::setenv("WATCHDOG_PID", "1", 1);  // the watchdog is for pid 1, not for us
  hd::ServiceNotifier n;
  ASSERT_EQ(n.open(), "");
  EXPECT_EQ(n.watchdog_interval_ns(), 0U);
  n.feed(0);
  EXPECT_EQ(manager.receive(), "");
  n.ready("up");
  EXPECT_EQ(manager.receive(), "READY=1\nSTATUS=up");
}

TEST(ServiceNotifier, BadEnvironmentIsOneLineAndNoManagerIsCountedNotFatal) {
  {
    ::setenv("NOTIFY_SOCKET", "relative/path", 1);
    hd::ServiceNotifier n;
    EXPECT_NE(n.open().find("NOTIFY_SOCKET=relative/path"), std::string::npos);
    EXPECT_FALSE(n.active());
  }
  {
    SocketPath path;
    FakeServiceManager manager(path.str());
    ::setenv("WATCHDOG_USEC", "soon", 1);
    hd::ServiceNotifier n;
    EXPECT_NE(n.open().find("WATCHDOG_USEC=soon"), std::string::npos);
  }
  {
    // A socket nobody listens on: connect fails, said in one line.
    SocketPath path;
    ::setenv("NOTIFY_SOCKET", path.str().c_str(), 1);
    hd::ServiceNotifier n;
    EXPECT_NE(n.open().find(path.str()), std::string::npos);
    ::unsetenv("NOTIFY_SOCKET");
  }
  {
    // The manager goes away after the start: sends fail and are counted, nothing else.
    SocketPath path;
    hd::ServiceNotifier n;
    {
      FakeServiceManager manager(path.str());
      ASSERT_EQ(n.open(), "");
    }
    n.ready("x");
    n.status("y");
    EXPECT_EQ(n.sent(), 0U);
    EXPECT_EQ(n.failed(), 2U);
  }
}
