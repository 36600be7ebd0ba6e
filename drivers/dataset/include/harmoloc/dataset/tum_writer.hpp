#pragma once
/// @file A TUM trajectory output for the cycle: the file and its buffer are set up at start-up,
/// each pose is formatted into a stack buffer and appended without allocating.

#include <cstdint>
#include <cstdio>
#include <string>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/dataset/buffered_output.hpp"

namespace harmoloc::dataset {

class TumWriter {
 public:
  /// Opens (truncates) @p path; false if it cannot be written.
  bool open(const std::string& path) { return out_.open(path); }
  /// Appends one pose; does nothing when no file is open.
  void write(std::uint64_t t_ns, const algorithms::Pose2& pose);
  /// Flushes and closes; false if any write failed.
  bool close() { return out_.close(); }
  const BufferedOutput& output() const { return out_; }

 private:
  BufferedOutput out_;
};

}  // namespace harmoloc::dataset
