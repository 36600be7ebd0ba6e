#pragma once
/// @file Helpers shared by the fuzz targets: a private scratch directory per process (the
/// file-based parsers take a path) and a finding that aborts with a message.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <fcntl.h>
#include <unistd.h>

#include <filesystem>

namespace harmoloc::fuzz {

/// A directory of this process's own under $TMPDIR (or /tmp), removed at exit. Unique per
/// process (mkdtemp), so several fuzzers, or a fuzzer and the test suite, never share a file.
inline const std::string& scratch_dir() {
  static const std::string dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern =
        std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/harmoloc-fuzz-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      std::perror("mkdtemp");
      std::abort();
    }
    static std::string for_cleanup;
    for_cleanup = pattern;
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(for_cleanup, ec);
    });
    return pattern;
  }();
  return dir;
}

/// Replaces @p path's content with @p data. Aborts if the write fails: a fuzzer that
/// silently tests a stale file would report nothing while testing nothing.
inline void write_file(const std::string& path, const std::uint8_t* data, std::size_t size) {
  // No O_TRUNC: ext4 (auto_da_alloc) flushes a file truncated to 0 and rewritten on close,
  // which made each run wait for the disk. Overwrite, then cut to size.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0600);
  if (fd < 0) {
    std::perror(path.c_str());
    std::abort();
  }
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n <= 0) {
      std::perror(path.c_str());
      std::abort();
    }
    done += static_cast<std::size_t>(n);
  }
  if (::ftruncate(fd, static_cast<off_t>(size)) != 0) {
    std::perror(path.c_str());
    std::abort();
  }
  ::close(fd);
}

/// A property the parser must keep does not hold: report and abort (libFuzzer saves the input).
[[noreturn]] inline void finding(const char* what) {
  std::fprintf(stderr, "\n==harmoloc-fuzz== FINDING: %s\n", what);
  std::fflush(stderr);
  std::abort();
}

#define HARMOLOC_FUZZ_CHECK(cond, what)                          \
  do {                                                           \
    if (!(cond)) ::harmoloc::fuzz::finding(what " (" #cond ")"); \
  } while (0)

}  // namespace harmoloc::fuzz
