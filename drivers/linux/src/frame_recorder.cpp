#include "harmoloc/drivers/frame_recorder.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>

namespace harmoloc::drivers {
namespace {

// Writes all of @p iov or fails (short writes are retried); false with errno set.
bool write_all(int fd, iovec* iov, int count) {
  while (count > 0) {
    const ssize_t n = ::writev(fd, iov, count);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    auto left = static_cast<std::size_t>(n);
    while (count > 0 && left >= iov->iov_len) {
      left -= iov->iov_len;
      ++iov;
      --count;
    }
    if (count > 0) {
      iov->iov_base = static_cast<char*>(iov->iov_base) + left;
      iov->iov_len -= left;
    }
  }
  return true;
}

}  // namespace

std::string FrameRecorder::start(const std::string& dir, std::uint32_t width_px,
                                 std::uint32_t height_px, hal::PixelFormat format,
                                 const FrameRecorderOptions& options) {
  if (started_) return "frame recorder already started";
  if (width_px == 0 || height_px == 0) return "frame size unknown";
  if (format == hal::PixelFormat::kYuyv && width_px % 2 != 0)
    return "a YUYV frame must be an even number of pixels wide";
  dir_ = dir;
  width_px_ = width_px;
  height_px_ = height_px;
  format_ = format;
  options_ = options;
  if (options_.every_n == 0) options_.every_n = 1;
  row_bytes_ = std::size_t{width_px} * (format == hal::PixelFormat::kRgb24 ? 3U : 2U);
  const std::string frames_dir = dir + "/frames";
  if (::mkdir(frames_dir.c_str(), 0755) != 0 && errno != EEXIST)
    return frames_dir + ": cannot create (" + std::strerror(errno) + ")";
  const std::string index = dir + "/frames.csv";
  index_fd_ = ::open(index.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (index_fd_ < 0) return index + ": cannot write (" + std::strerror(errno) + ")";
  static const char kHeader[] = "timestamp_ns,file\n";
  if (::write(index_fd_, kHeader, sizeof kHeader - 1) != static_cast<ssize_t>(sizeof kHeader - 1))
    return index + ": cannot write (" + std::strerror(errno) + ")";
  for (std::uint32_t i = 0; i < kSlots; ++i) {
    slots_[i].bytes.assign(row_bytes_ * height_px, 0);  // touched now, not in the cycle
    free_.push(i);
  }
  started_ = true;
  writer_ = std::thread([this] { writer_loop(); });
  return "";
}

void FrameRecorder::offer(const hal::FrameView& frame) {
  if (!active()) return;
  if (frame.width_px != width_px_ || frame.height_px != height_px_ || frame.format != format_ ||
      frame.data == nullptr || frame.stride_bytes < row_bytes_) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (offered_ == 0) first_ns_ = frame.timestamp_ns;
  if (options_.max_duration_ns != 0 && frame.timestamp_ns - first_ns_ >= options_.max_duration_ns) {
    std::uint8_t none = 0;
    stop_reason_.compare_exchange_strong(none, static_cast<std::uint8_t>(RecordingStop::kTimeLimit),
                                         std::memory_order_acq_rel);
    return;
  }
  const bool due = offered_ % options_.every_n == 0;
  ++offered_;
  if (!due) {
    ++skipped_;
    return;
  }
  std::uint32_t index = 0;
  bool got = free_.pop(index);
  // An unpaced replay waits while the writer works (it hands every slot back, even after a stop).
  while (!got && options_.wait_for_disk && stop_reason() == RecordingStop::kNone) {
    timespec nap{0, 200'000};
    ::nanosleep(&nap, nullptr);
    got = free_.pop(index);
  }
  if (!got) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  Slot& slot = slots_[index];
  for (std::uint32_t row = 0; row < height_px_; ++row) {
    std::memcpy(slot.bytes.data() + row * row_bytes_,
                frame.data + std::size_t{row} * frame.stride_bytes, row_bytes_);
  }
  slot.timestamp_ns = frame.timestamp_ns;
  filled_.push(index);  // cannot be full: there are as many slots as ring places
}

void FrameRecorder::fail(int error, const char* path) {
  std::snprintf(failed_path_.data(), failed_path_.size(), "%s", path);
  error_.store(error != 0 ? error : EIO, std::memory_order_release);
  std::uint8_t none = 0;
  stop_reason_.compare_exchange_strong(none, static_cast<std::uint8_t>(RecordingStop::kWriteFailed),
                                       std::memory_order_acq_rel);
}

bool FrameRecorder::write_slot(const Slot& slot) {
  const std::size_t frame_bytes = slot.bytes.size();
  char header[48];
  int header_len = 0;
  if (format_ == hal::PixelFormat::kRgb24)
    header_len = std::snprintf(header, sizeof header, "P6\n%u %u\n255\n", width_px_, height_px_);
  if (options_.max_bytes != 0 &&
      bytes_.load(std::memory_order_relaxed) + frame_bytes + static_cast<std::size_t>(header_len) >
          options_.max_bytes) {
    std::uint8_t none = 0;
    stop_reason_.compare_exchange_strong(none, static_cast<std::uint8_t>(RecordingStop::kSizeLimit),
                                         std::memory_order_acq_rel);
    return false;
  }
  char name[32];
  std::snprintf(name, sizeof name, "frames/%06llu.%s",
                static_cast<unsigned long long>(file_number_),
                format_ == hal::PixelFormat::kRgb24 ? "ppm" : "yuyv");
  char path[1024];
  std::snprintf(path, sizeof path, "%s/%s", dir_.c_str(), name);
  const int fd = ::open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    fail(errno, path);
    return false;
  }
  iovec iov[2] = {{header, static_cast<std::size_t>(header_len)},
                  {const_cast<std::uint8_t*>(slot.bytes.data()), frame_bytes}};
  const bool ok = write_all(fd, header_len > 0 ? iov : iov + 1, header_len > 0 ? 2 : 1);
  const int write_errno = errno;
  if (::close(fd) != 0 || !ok) {
    fail(ok ? errno : write_errno, path);
    return false;
  }
  char line[64];
  const int line_len = std::snprintf(line, sizeof line, "%llu,%s\n",
                                     static_cast<unsigned long long>(slot.timestamp_ns), name);
  iovec line_iov{line, static_cast<std::size_t>(line_len)};
  if (!write_all(index_fd_, &line_iov, 1)) {
    std::snprintf(path, sizeof path, "%s/frames.csv", dir_.c_str());
    fail(errno, path);
    return false;
  }
  ++file_number_;
  bytes_.fetch_add(frame_bytes + static_cast<std::size_t>(header_len), std::memory_order_relaxed);
  recorded_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

void FrameRecorder::writer_loop() {
  for (;;) {
    std::uint32_t index = 0;
    const bool held = hold_.load(std::memory_order_acquire);
    hold_seen_.store(held, std::memory_order_release);
    if (!held && filled_.pop(index)) {
      // Frames queued before the time limit are still written; after a failed write or the size
      // limit the slots are only handed back (so nothing waits).
      const RecordingStop reason = stop_reason();
      if (reason == RecordingStop::kNone || reason == RecordingStop::kTimeLimit)
        write_slot(slots_[index]);
      free_.push(index);
      continue;
    }
    if (quit_.load(std::memory_order_acquire) && (held || filled_.size() == 0)) return;
    // The cycle never waits for this thread, so polling costs only a wake-up every 2 ms.
    timespec nap{0, 2'000'000};
    ::nanosleep(&nap, nullptr);
  }
}

void FrameRecorder::hold_writer_for_test(bool hold) {
  hold_.store(hold, std::memory_order_release);
  if (!hold || !started_) return;
  for (int i = 0; i < 5000 && !hold_seen_.load(std::memory_order_acquire); ++i) {
    timespec nap{0, 1'000'000};
    ::nanosleep(&nap, nullptr);
  }
}

void FrameRecorder::stop() {
  if (!started_) return;
  hold_.store(false, std::memory_order_release);
  quit_.store(true, std::memory_order_release);
  if (writer_.joinable()) writer_.join();
  if (index_fd_ >= 0 && ::close(index_fd_) != 0 && stop_reason() == RecordingStop::kNone) {
    const std::string index = dir_ + "/frames.csv";
    fail(errno, index.c_str());
  }
  index_fd_ = -1;
  started_ = false;
}

FrameRecorderCounters FrameRecorder::counters() const {
  FrameRecorderCounters c;
  c.offered = offered_;
  c.skipped = skipped_;
  c.dropped = dropped_.load(std::memory_order_relaxed);
  c.recorded = recorded_.load(std::memory_order_relaxed);
  c.bytes = bytes_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace harmoloc::drivers
