#pragma once

// What every dataset reader starts with: the whole text file of a recording.

#include <stdexcept>
#include <string>

#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::dataset::detail {

// The file at @p path, whole: a regular file of at most input_limits::kRecordingBytes, or
// std::runtime_error "PATH: why".
inline std::string read_recording_text(const std::string& path) {
  std::string content;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kRecordingBytes, content);
      !e.empty()) {
    throw std::runtime_error(path + ": " + e);
  }
  return content;
}

}  // namespace harmoloc::dataset::detail
