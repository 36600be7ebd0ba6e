#pragma once
/// @file can-utils `candump -l` log files: `(sec.usec) iface ID#HEXDATA` a line, the same file
/// a robot's bus gives and `canplayer` replays.

#include <string>
#include <vector>

#include "harmoloc/algorithms/can_encoder_layout.hpp"

namespace harmoloc::dataset {

/// Parses one log line. Returns false with a reason for a malformed line (remote frames and
/// CAN FD frames are reported as unsupported).
bool parse_candump_line(const std::string& line, algorithms::CanFrame& frame, std::string& reason);

/// Reads a whole log. Throws std::runtime_error("FILE:LINE: reason") on a malformed line.
std::vector<algorithms::CanFrame> read_candump_log(const std::string& path);

std::string format_candump_line(const algorithms::CanFrame& frame, const std::string& iface);

}  // namespace harmoloc::dataset
