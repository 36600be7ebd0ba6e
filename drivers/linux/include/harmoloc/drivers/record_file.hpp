#pragma once
/// @file hal::PersistentRecord as a file: each record replaces the file whole (written to
/// FILE.tmp, fsync'ed, renamed over FILE), so a crash or power cut leaves the old record or the
/// new one, never a mix. The writes happen on a thread of their own: offer() copies the record
/// under a mutex it only try-locks, so the cycle never waits for the disk.

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

#include "harmoloc/hal/persistent_record.hpp"

namespace harmoloc::drivers {

class RecordFile final : public hal::PersistentRecord {
 public:
  RecordFile() = default;
  ~RecordFile();
  RecordFile(const RecordFile&) = delete;
  RecordFile& operator=(const RecordFile&) = delete;

  /// Writes @p size bytes to @p path the same way, now, on the calling thread (start-up).
  /// Returns an empty string, or the reason.
  static std::string write_now(const std::string& path, const std::uint8_t* bytes,
                               std::size_t size);

  /// Starts the writer thread for @p path, with @p tag as the record already on storage.
  void start(const std::string& path, std::uint64_t durable_tag);
  /// Writes what was offered and not written yet, then stops the thread.
  void stop();

  bool offer(const std::uint8_t* bytes, std::size_t size, std::uint64_t tag) override;
  std::uint64_t durable_tag() const override { return durable_.load(std::memory_order_acquire); }
  std::uint64_t failures() const override { return failures_.load(std::memory_order_relaxed); }

 private:
  void run();
  /// Writes @p size bytes to @p tmp, fsyncs it and renames it over @p path. Returns 0 or the
  /// errno of the step that failed (@p step says which). No allocation.
  static int write_file(const char* path, const char* tmp, const std::uint8_t* bytes,
                        std::size_t size, const char** step);

  std::string path_;
  std::string tmp_path_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::array<std::uint8_t, kMaxBytes> pending_{};  // guarded by mutex_
  std::size_t pending_size_ = 0;                   // guarded by mutex_
  std::uint64_t pending_tag_ = 0;                  // guarded by mutex_; 0: nothing pending
  bool stopping_ = false;                          // guarded by mutex_
  std::atomic<std::uint64_t> durable_{0};
  std::atomic<std::uint64_t> failures_{0};
  std::thread thread_;
};

}  // namespace harmoloc::drivers
