// Helpers shared by the unit tests (header-only): a scratch directory per test, whole-file reads
// and writes, catching an expected error's message and checking that it is one clear line, and
// the six boards' colour windows.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::test {

// --- files ---------------------------------------------------------------------------------------

/// The whole file at @p path as bytes (empty if it cannot be read).
inline std::vector<std::uint8_t> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
}

/// Replaces the contents of the file at @p path with @p bytes.
inline void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

/// Replaces the contents of the file at @p path with @p text, byte for byte (no newline mapping).
inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

/// A fresh, empty directory for the running test, removed with everything in it at the end of
/// scope. Its name holds the test suite, the test, the process id and a per-process count, so
/// tests that run at the same time (ctest -j) and two TempDirs in one test never share it.
class TempDir {
 public:
  TempDir() {
    const auto* info = testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "harmoloc_test_" + std::to_string(::getpid()) + "_" +
                       std::to_string(next_number()) + "_" +
                       (info != nullptr ? std::string(info->test_suite_name()) + "_" + info->name()
                                        : std::string("no_test"));
    for (char& c : name) {
      if (c == '/') c = '_';  // parameterised tests are called "Prefix/Suite.Name/3"
    }
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  /// The directory itself.
  std::string dir() const { return path_.string(); }
  /// The path of @p name in the directory (for "", the directory with a trailing '/').
  std::string path(const std::string& name = "") const { return (path_ / name).string(); }
  /// Creates the sub-directory @p name (and its parents) and returns its path.
  std::string mkdir(const std::string& name) const {
    std::filesystem::create_directories(path_ / name);
    return path(name);
  }
  /// Writes the file @p name with @p text and returns its path.
  std::string write(const std::string& name, const std::string& text) const {
    write_text(path(name), text);
    return path(name);
  }
  /// Writes the file @p name with @p bytes and returns its path.
  std::string write_bytes(const std::string& name, const std::vector<std::uint8_t>& bytes) const {
    test::write_bytes(path(name), bytes);
    return path(name);
  }

 private:
  static int next_number() {
    static std::atomic<int> count{0};
    return count++;
  }

  std::filesystem::path path_;
};

// --- error messages ------------------------------------------------------------------------------

/// What error_of() returns when nothing was thrown.
inline const std::string kNoException = "(no exception)";

/// Runs @p f, which is expected to throw std::runtime_error, and returns the message (kNoException
/// if it returned normally; any other exception passes through and fails the test).
template <typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return kNoException;
}

/// Expects @p msg to be a single line that starts with @p prefix (typically "<file>: ") and
/// contains @p what.
inline void expect_one_line(const std::string& msg, const std::string& prefix,
                            const std::string& what = "") {
  EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  EXPECT_EQ(msg.rfind(prefix, 0), 0U) << "expected to start with '" << prefix << "': " << msg;
  EXPECT_NE(msg.find(what), std::string::npos) << "expected '" << what << "' in: " << msg;
}

// --- colour windows ------------------------------------------------------------------------------

/// Hue windows (degrees, min then max) of the six boards red, green, blue, yellow, magenta and
/// cyan; red wraps through 0. The firmware's defaults, except red: its default is now [345, 10]
/// (docs/training.md, lighting); the tests keep the wider window they were written for.
inline constexpr float kBoardHuesDeg[6][2] = {{340, 15}, {100, 145}, {215, 250},
                                              {45, 70},  {285, 320}, {170, 200}};

/// The first @p count of those six boards with the firmware's default saturation minimum 110 and
/// value range 60..255.
inline algorithms::ThresholdSet board_windows(std::size_t count = 6) {
  algorithms::ThresholdSet t;
  t.count = count;
  for (std::size_t i = 0; i < count; ++i) {
    t.boards[i] =
        algorithms::ColourThreshold{kBoardHuesDeg[i][0], kBoardHuesDeg[i][1], 110, 60, 255};
  }
  return t;
}

}  // namespace harmoloc::test
