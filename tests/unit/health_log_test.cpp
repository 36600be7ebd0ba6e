// Health changes as the journal receives them: stderr replaced by one end of a socket pair
// (systemd connects a service's stderr to the journal with a stream socket), JOURNAL_STREAM
// naming it as systemd does.

#include "health_log.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <string>

namespace hb = harmoloc::boards;
using harmoloc::firmware::Health;

namespace {

constexpr std::uint64_t kSecond = 1'000'000'000;

// stderr goes to a socket pair for the test's lifetime; read() returns what was written.
class CapturedStderr {
 public:
  explicit CapturedStderr(bool name_as_journal) {
    ::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair_);
    saved_ = ::dup(STDERR_FILENO);
    ::dup2(pair_[0], STDERR_FILENO);
    struct stat st {};
    ::fstat(STDERR_FILENO, &st);
    if (name_as_journal)
      ::setenv("JOURNAL_STREAM",
               (std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino)).c_str(), 1);
    else
      ::setenv("JOURNAL_STREAM", "1:2", 1);  // inherited from a parent, not ours
  }
  ~CapturedStderr() {
    ::dup2(saved_, STDERR_FILENO);
    ::close(saved_);
    ::close(pair_[0]);
    ::close(pair_[1]);
    ::unsetenv("JOURNAL_STREAM");
  }
  std::string read() {
    char buf[4096];
    const ssize_t n = ::recv(pair_[1], buf, sizeof buf, MSG_DONTWAIT);
    return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
  }

 private:
  int pair_[2] = {-1, -1};
  int saved_ = -1;
};

}  // namespace

TEST(HealthLog, ChangesWithJournalPrioritiesAndFlappingOnceASecond) {
  CapturedStderr err(true);
  hb::HealthLog log;
  log.start();
  std::uint64_t t = 100 * kSecond;
  EXPECT_EQ(log.observe(Health::kNotInitialized, false, t), nullptr);  // no change: nothing
  EXPECT_EQ(err.read(), "");
  ASSERT_NE(log.observe(Health::kNominal, false, t += 1000), nullptr);
  EXPECT_EQ(err.read(), "<5>harmoloc: health nominal (was not_initialized)\n");
  for (int i = 0; i < 10; ++i) log.observe(Health::kNominal, false, t += kSecond / 30);
  EXPECT_EQ(err.read(), "");
  // Flapping: the first change is said at once (a second has passed), the rest a second later.
  log.observe(Health::kVisionOnly, false, t += kSecond);
  EXPECT_EQ(err.read(), "<4>harmoloc: health vision_only (was nominal)\n");
  for (int i = 0; i < 6; ++i)
    log.observe(i % 2 ? Health::kVisionOnly : Health::kOdometryOnly, false, t += kSecond / 30);
  log.observe(Health::kInvalid, false, t += kSecond / 30);
  EXPECT_EQ(err.read(), "");
  log.observe(Health::kInvalid, false, t += kSecond);
  EXPECT_EQ(err.read(), "<3>harmoloc: health invalid (was vision_only; 6 changes in between)\n");
  // The overrun alarm: at once, both ways.
  log.observe(Health::kInvalid, true, t += 1000);
  EXPECT_EQ(err.read(), "<4>harmoloc: cycle overrun: the cycle is over its budget\n");
  log.observe(Health::kInvalid, false, t += 1000);
  EXPECT_EQ(err.read(), "<5>harmoloc: cycle overrun cleared\n");
  EXPECT_EQ(log.lines(), 5U);
  EXPECT_EQ(log.lost(), 0U);
}

TEST(HealthLog, NoPriorityPrefixWhenStderrIsNotTheJournal) {
  CapturedStderr err(false);
  hb::HealthLog log;
  log.start();
  log.observe(Health::kNominal, false, kSecond);
  EXPECT_EQ(err.read(), "harmoloc: health nominal (was not_initialized)\n");
}
