#pragma once
/// @file A text output the cycle can append to: the file and a 64 KiB stdio buffer are set up at
/// start-up, so no write after that allocates (stdio would otherwise allocate on the first one).

#include <cstddef>
#include <cstdio>
#include <string>

namespace harmoloc::dataset {

class BufferedOutput {
 public:
  BufferedOutput() = default;
  ~BufferedOutput() { close(); }
  BufferedOutput(const BufferedOutput&) = delete;
  BufferedOutput& operator=(const BufferedOutput&) = delete;

  /// Opens (truncates) @p path; false if it cannot be written.
  bool open(const std::string& path);
  bool is_open() const { return file_ != nullptr; }
  /// The open file, for formatted writes at start-up (nullptr when closed).
  std::FILE* file() { return file_; }
  /// Appends @p size bytes; does nothing when no file is open.
  void append(const char* bytes, std::size_t size);
  /// Flushes and closes; false if any write failed.
  bool close();
  /// The errno of the first write that failed (0: none so far). A write fails when stdio flushes
  /// its buffer (every 64 KiB) or at close(): the caller can say so when it happens.
  int error() const { return error_; }
  /// The path given to open().
  const std::string& path() const { return path_; }

 private:
  static constexpr std::size_t kBufferBytes = 1 << 16;
  std::FILE* file_ = nullptr;
  char* buffer_ = nullptr;
  int error_ = 0;
  std::string path_;
};

}  // namespace harmoloc::dataset
