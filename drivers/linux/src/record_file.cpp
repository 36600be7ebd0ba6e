#include "harmoloc/drivers/record_file.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

namespace harmoloc::drivers {

int RecordFile::write_file(const char* path, const char* tmp, const std::uint8_t* bytes,
                           std::size_t size, const char** step) {
  *step = "cannot create";
  const int fd = ::open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) return errno;
  std::size_t done = 0;
  *step = "write failed";
  while (done < size) {
    const ssize_t n = ::write(fd, bytes + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int e = n < 0 ? errno : EIO;
      ::close(fd);
      return e;
    }
    done += static_cast<std::size_t>(n);
  }
  *step = "fsync failed";
  if (::fsync(fd) != 0) {
    const int e = errno;
    ::close(fd);
    return e;
  }
  *step = "close failed";
  if (::close(fd) != 0) return errno;
  *step = "cannot replace the file";
  if (::rename(tmp, path) != 0) return errno;
  return 0;
}

std::string RecordFile::write_now(const std::string& path, const std::uint8_t* bytes,
                                  std::size_t size) {
  const std::string tmp = path + ".tmp";
  const char* step = "";
  const int e = write_file(path.c_str(), tmp.c_str(), bytes, size, &step);
  if (e == 0) return {};
  return tmp + ": " + step + " (" + std::strerror(e) + ")";
}

RecordFile::~RecordFile() {
  stop();
}

void RecordFile::start(const std::string& path, std::uint64_t durable_tag) {
  stop();
  path_ = path;
  tmp_path_ = path + ".tmp";
  durable_.store(durable_tag, std::memory_order_release);
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = false;
    pending_tag_ = 0;
  }
  thread_ = std::thread([this] { run(); });
}

void RecordFile::stop() {
  if (!thread_.joinable()) return;
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  thread_.join();
}

bool RecordFile::offer(const std::uint8_t* bytes, std::size_t size, std::uint64_t tag) {
  if (size > kMaxBytes || tag == 0) return false;
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || stopping_ || !thread_.joinable()) return false;
  std::copy(bytes, bytes + size, pending_.begin());
  pending_size_ = size;
  pending_tag_ = tag;
  lock.unlock();
  wake_.notify_one();
  return true;
}

void RecordFile::run() {
  std::array<std::uint8_t, kMaxBytes> record{};
  for (;;) {
    std::size_t size = 0;
    std::uint64_t tag = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return pending_tag_ != 0 || stopping_; });
      if (pending_tag_ == 0) return;  // stopping, nothing left to write
      size = pending_size_;
      tag = pending_tag_;
      std::copy(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(size),
                record.begin());
      pending_tag_ = 0;
    }
    const char* step = "";
    if (write_file(path_.c_str(), tmp_path_.c_str(), record.data(), size, &step) == 0) {
      if (tag > durable_.load(std::memory_order_relaxed))
        durable_.store(tag, std::memory_order_release);
    } else {
      failures_.fetch_add(1, std::memory_order_relaxed);
    }
  }
}

}  // namespace harmoloc::drivers
