#include "harmoloc/drivers/gpio_quadrature_encoders.hpp"

#include <cerrno>
#include <cstring>
#include <ctime>

#include <gpiod.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

namespace harmoloc::drivers {

namespace {

std::uint64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

std::uint64_t event_ns(const gpiod_line_event& e) {
  return static_cast<std::uint64_t>(e.ts.tv_sec) * 1000000000ULL +
         static_cast<std::uint64_t>(e.ts.tv_nsec);
}

constexpr const char* kConsumer = "harmoloc";
constexpr std::size_t kEventsPerRead = 16;  // the v1 API's kernel queue per line

}  // namespace

GpioQuadratureEncoders::~GpioQuadratureEncoders() {
  if (reader_.joinable()) {
    const std::uint64_t one = 1;
    if (::write(stop_fd_, &one, sizeof one) < 0) {
    }
    reader_.join();
  }
  close_all();
}

void GpioQuadratureEncoders::close_all() {
  for (gpiod_line*& l : lines_) {
    if (l != nullptr) gpiod_line_release(l);
    l = nullptr;
  }
  fds_.fill(-1);
  if (chip_ != nullptr) gpiod_chip_close(chip_);
  chip_ = nullptr;
  if (stop_fd_ >= 0) ::close(stop_fd_);
  stop_fd_ = -1;
}

std::string GpioQuadratureEncoders::open(const GpioEncoderOptions& options) {
  options_ = options;
  const std::string where = "GPIO chip " + options.chip + ": ";
  chip_ = gpiod_chip_open_lookup(options.chip.c_str());
  if (chip_ == nullptr) return where + std::strerror(errno);
  const unsigned offsets[kLines] = {options.left_lines[0], options.left_lines[1],
                                    options.right_lines[0], options.right_lines[1]};
  static constexpr const char* kNames[kLines] = {"left A", "left B", "right A", "right B"};
  for (std::size_t i = 0; i < kLines; ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (offsets[i] == offsets[j]) {
        return where + "line " + std::to_string(offsets[i]) + " is given twice (" + kNames[j] +
               ", " + kNames[i] + ")";
      }
    }
    if (offsets[i] >= gpiod_chip_num_lines(chip_)) {
      return where + kNames[i] + " line " + std::to_string(offsets[i]) + " does not exist (" +
             std::to_string(gpiod_chip_num_lines(chip_)) + " lines)";
    }
    lines_[i] = gpiod_chip_get_line(chip_, offsets[i]);
    if (lines_[i] == nullptr)
      return where + kNames[i] + " line " + std::to_string(offsets[i]) + ": " +
             std::strerror(errno);
    if (gpiod_line_request_both_edges_events(lines_[i], kConsumer) < 0) {
      const int e = errno;
      lines_[i] = nullptr;
      return where + kNames[i] + " line " + std::to_string(offsets[i]) + ": " + std::strerror(e) +
             (e == EBUSY ? " (used by another program)" : "");
    }
    fds_[i] = gpiod_line_event_get_fd(lines_[i]);
    if (fds_[i] < 0) return where + kNames[i] + ": no event descriptor";
  }
  int levels[kLines];
  for (std::size_t i = 0; i < kLines; ++i) {
    levels[i] = gpiod_line_get_value(lines_[i]);
    if (levels[i] < 0)
      return where + kNames[i] + ": cannot read its level: " + std::strerror(errno);
  }
  const std::uint64_t debounce_ns = std::uint64_t{options.debounce_us} * 1000ULL;
  decoders_[0].reset(levels[0] != 0, levels[1] != 0, debounce_ns);
  decoders_[1].reset(levels[2] != 0, levels[3] != 0, debounce_ns);
  publish();
  description_ = std::string(gpiod_chip_name(chip_)) + " (" + gpiod_chip_label(chip_) +
                 "), lines left " + std::to_string(offsets[0]) + "/" + std::to_string(offsets[1]) +
                 ", right " + std::to_string(offsets[2]) + "/" + std::to_string(offsets[3]) +
                 ", debounce " + std::to_string(options.debounce_us) + " us, " +
                 (options.reader == GpioReader::kThread ? "reader thread" : "read each cycle");
  if (options.reader == GpioReader::kThread) {
    stop_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (stop_fd_ < 0) return where + "eventfd: " + std::strerror(errno);
    try {
      reader_ = std::thread([this] { reader_loop(); });
    } catch (const std::exception& e) {
      return where + "cannot start the reader thread: " + e.what();
    }
  }
  return {};
}

bool GpioQuadratureEncoders::service(std::uint64_t now_ns) {
  if (failed_) return false;
  for (std::size_t wheel = 0; wheel < 2; ++wheel) {
    // Both lines of the wheel, merged by timestamp (each line's queue is already in order).
    std::array<std::array<gpiod_line_event, kEventsPerRead>, 2> events{};
    std::array<std::size_t, 2> count{};
    for (std::size_t k = 0; k < 2; ++k) {
      const int fd = fds_[2 * wheel + k];
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 0) <= 0 || (p.revents & POLLIN) == 0) continue;
      const int n = gpiod_line_event_read_fd_multiple(fd, events[k].data(),
                                                      static_cast<unsigned>(kEventsPerRead));
      if (n < 0) {
        if (errno == EAGAIN || errno == EINTR) continue;
        failed_ = true;
        publish();
        return false;
      }
      count[k] = static_cast<std::size_t>(n);
    }
    algorithms::QuadratureDecoder& d = decoders_[wheel];
    std::array<std::size_t, 2> next{};
    while (next[0] < count[0] || next[1] < count[1]) {
      std::size_t k = 0;
      if (next[0] >= count[0] ||
          (next[1] < count[1] && event_ns(events[1][next[1]]) < event_ns(events[0][next[0]]))) {
        k = 1;
      }
      const gpiod_line_event& e = events[k][next[k]++];
      d.edge(static_cast<std::uint8_t>(k), e.event_type == GPIOD_LINE_EVENT_RISING_EDGE,
             event_ns(e));
    }
    d.commit_until(now_ns);
    if (count[0] + count[1] > 0) {
      quiet_mismatch_[wheel] = 0;
      continue;
    }
    // A quiet pass: do the lines agree with the decoded state? Only a disagreement seen in two
    // quiet passes in a row counts (an edge may be on its way from the kernel in the first).
    if (d.pending()) continue;
    const int a = gpiod_line_get_value(lines_[2 * wheel]);
    const int b = gpiod_line_get_value(lines_[2 * wheel + 1]);
    if (a < 0 || b < 0) {
      failed_ = true;
      publish();
      return false;
    }
    const auto real = static_cast<std::uint8_t>((a != 0 ? 2U : 0U) | (b != 0 ? 1U : 0U));
    if (real == d.state()) {
      quiet_mismatch_[wheel] = 0;
    } else if (++quiet_mismatch_[wheel] >= 2) {
      const std::uint64_t glitches_before = d.glitches();
      d.resync(a != 0, b != 0);
      if (d.glitches() == glitches_before) ++overflows_;  // one lost edge, direction known
      quiet_mismatch_[wheel] = 0;
    }
  }
  publish();
  return true;
}

void GpioQuadratureEncoders::publish() {
  CountSnapshot snapshot;
  snapshot.left = decoders_[0].position();
  snapshot.right = decoders_[1].position();
  snapshot.glitches = decoders_[0].glitches() + decoders_[1].glitches();
  snapshot.overflows = overflows_;
  snapshot.failed = failed_;
  shared_.publish(snapshot);
}

void GpioQuadratureEncoders::reader_loop() {
  std::array<pollfd, kLines + 1> p{};
  for (std::size_t i = 0; i < kLines; ++i) p[i] = pollfd{fds_[i], POLLIN, 0};
  p[kLines] = pollfd{stop_fd_, POLLIN, 0};
  // Wake at least this often: debounced edges are committed and quiet lines checked.
  const int idle_ms = 20;
  for (;;) {
    for (pollfd& q : p) q.revents = 0;
    const int rc = ::poll(p.data(), p.size(), idle_ms);
    if (rc < 0 && errno != EINTR) {
      failed_ = true;
      publish();
      return;
    }
    if ((p[kLines].revents & POLLIN) != 0) return;
    if (!service(monotonic_ns())) return;
  }
}

hal::EncoderStatus GpioQuadratureEncoders::read(std::uint64_t data_time_ns,
                                                hal::EncoderCounts& counts) {
  if (options_.reader == GpioReader::kCycle) service(monotonic_ns());
  // Sequence lock, reader side: a few tries; the writer holds it for a handful of stores.
  CountSnapshot snapshot;
  if (!shared_.read(snapshot)) return hal::EncoderStatus::kNoData;  // next cycle
  if (snapshot.failed) return hal::EncoderStatus::kNoData;
  counts.left_ticks = static_cast<std::uint32_t>(static_cast<std::uint64_t>(snapshot.left));
  counts.right_ticks = static_cast<std::uint32_t>(static_cast<std::uint64_t>(snapshot.right));
  counts.counter_bits = 32;
  counts.timestamp_ns = data_time_ns != 0 ? data_time_ns : monotonic_ns();
  ++samples_;
  return hal::EncoderStatus::kFresh;
}

hal::EncoderCounters GpioQuadratureEncoders::counters() const {
  hal::EncoderCounters c;
  c.samples = samples_;
  c.glitches = shared_.glitches();
  c.overflows = shared_.overflows();
  c.bus_errors = shared_.failed() ? 1 : 0;
  return c;
}

std::int64_t GpioQuadratureEncoders::left_position() const {
  return shared_.left();
}
std::int64_t GpioQuadratureEncoders::right_position() const {
  return shared_.right();
}

}  // namespace harmoloc::drivers
