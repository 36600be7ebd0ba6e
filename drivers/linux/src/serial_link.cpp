#include "harmoloc/drivers/serial_link.hpp"

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

namespace harmoloc::drivers {

namespace {

speed_t baud_constant(unsigned baud) {
  switch (baud) {
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    case 115200:
      return B115200;
    case 230400:
      return B230400;
    case 460800:
      return B460800;
    case 921600:
      return B921600;
    default:
      return B0;
  }
}

}  // namespace

SerialLink::~SerialLink() {
  if (in_fd_ >= 0 && in_fd_ != fd_) ::close(in_fd_);
  if (fd_ >= 0) ::close(fd_);
}

std::string SerialLink::open(const std::string& path, unsigned baud) {
  struct stat st {};
  const bool exists = ::stat(path.c_str(), &st) == 0;
  if (exists && S_ISCHR(st.st_mode)) {
    // Read-write so that a peer's commands can come back on the same line; a device this user
    // may only write to still carries the pose.
    bool readable = true;
    fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0 && (errno == EACCES || errno == EPERM || errno == EROFS)) {
      readable = false;
      fd_ = ::open(path.c_str(), O_WRONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    }
    if (fd_ < 0) return path + ": " + std::strerror(errno);
    if (::isatty(fd_) != 0) {
      is_tty_ = true;
      if (readable && in_fd_ < 0) in_fd_ = fd_;
      const speed_t speed = baud_constant(baud);
      if (speed == B0) return "unsupported baud rate " + std::to_string(baud);
      termios tio{};
      if (tcgetattr(fd_, &tio) != 0) return path + ": tcgetattr: " + std::strerror(errno);
      cfmakeraw(&tio);
      cfsetispeed(&tio, speed);
      cfsetospeed(&tio, speed);
      tio.c_cflag |= CLOCAL;
      if (tcsetattr(fd_, TCSANOW, &tio) != 0) return path + ": tcsetattr: " + std::strerror(errno);
    }
    return {};
  }
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NONBLOCK, 0644);
  if (fd_ < 0) return path + ": " + std::strerror(errno);
  return {};
}

std::string SerialLink::open_input(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return path + ": " + std::strerror(errno);
  if (in_fd_ >= 0 && in_fd_ != fd_) ::close(in_fd_);
  in_fd_ = fd;
  input_failed_ = false;
  return {};
}

std::size_t SerialLink::read_bytes(std::uint8_t* dst, std::size_t max) {
  if (in_fd_ < 0 || max == 0 || input_failed_) return 0;
  for (;;) {
    const ssize_t n = ::read(in_fd_, dst, max);
    if (n > 0) return static_cast<std::size_t>(n);
    if (n == 0) return 0;  // end of a file, or a FIFO with no writer
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) {
      // A hung-up line fails every read; one count says so, and output goes on as before.
      ++counters_.errors;
      input_failed_ = true;
    }
    return 0;
  }
}

bool SerialLink::flush_pending() {
  while (pending_sent_ < pending_size_) {
    const ssize_t n = ::write(fd_, pending_.data() + pending_sent_, pending_size_ - pending_sent_);
    if (n > 0) {
      pending_sent_ += static_cast<std::size_t>(n);
      counters_.bytes_sent += static_cast<std::uint64_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK) ++counters_.errors;
    return false;
  }
  pending_size_ = pending_sent_ = 0;
  return true;
}

hal::LinkWrite SerialLink::write_frame(const std::uint8_t* bytes, std::size_t size) {
  if (fd_ < 0) return hal::LinkWrite::kFailed;
  if (size > kMaxFrameBytes) {
    ++counters_.frames_dropped;
    return hal::LinkWrite::kDropped;
  }
  const std::uint64_t errors_at_start = counters_.errors;
  if (!flush_pending()) {
    ++counters_.frames_dropped;
    if (counters_.errors != errors_at_start) {  // hung up or I/O error: the rest will never go
      pending_size_ = pending_sent_ = 0;
      return hal::LinkWrite::kFailed;
    }
    return hal::LinkWrite::kDropped;
  }
  std::memcpy(pending_.data(), bytes, size);
  pending_size_ = size;
  pending_sent_ = 0;
  const std::uint64_t errors_before = counters_.errors;
  flush_pending();  // whatever does not go now goes first on the next write
  if (counters_.errors != errors_before) {
    pending_size_ = pending_sent_ = 0;
    return hal::LinkWrite::kFailed;
  }
  ++counters_.frames_sent;
  return hal::LinkWrite::kSent;
}

}  // namespace harmoloc::drivers
