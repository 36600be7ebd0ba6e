#pragma once
/// @file A text output the cycle can append to: the file and a 64 KiB stdio buffer are set up at
/// start-up, so no write after that allocates (stdio would otherwise allocate on the first one).

#include <cstddef>
#include <cstdio>
#include <string>

namespace harmoloc::sim_host {

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

 private:
  static constexpr std::size_t kBufferBytes = 1 << 16;
  std::FILE* file_ = nullptr;
  char* buffer_ = nullptr;
};

}  // namespace harmoloc::sim_host
