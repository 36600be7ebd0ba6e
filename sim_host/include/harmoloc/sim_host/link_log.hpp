#pragma once
/// @file What the report reads from a recorded link file (`harmoloc --link FILE`): the TUM files
/// carry no health and no spread, the link does. Each ODOMETRY gives a pose in the map frame with
/// its spread and quality (firmware/pose_messages.hpp); the health comes from the STATUSTEXTs
/// the firmware sends on each change (and, before the first, from HEARTBEAT). Decoded with the
/// firmware's own parser, as harmoloc-monitor does. Host only; allocates freely.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/firmware/pose_output.hpp"

namespace harmoloc::sim_host {

/// One ODOMETRY, back in the map frame.
struct LinkPose {
  double t_s = 0.0;  ///< the pose's data time (time_usec)
  algorithms::Pose2 pose;
  double sigma_m = 0.0;  ///< per-axis spread: sqrt of the mean of the x and y variances
  int quality = 0;       ///< 0..100; -1 invalid
  firmware::Health health = firmware::Health::kNotInitialized;
};

/// A stretch of time in one health. The firmware announces a change in the cycle it happens,
/// before that cycle's ODOMETRY, so a change is placed at the next pose's time. When several
/// changes come with no pose between them (the pose is not published while invalid), the ones
/// before the last share the gap since the previous pose.
struct HealthSpan {
  double start_s = 0.0;
  double end_s = 0.0;
  firmware::Health health = firmware::Health::kNotInitialized;
};

struct LinkLog {
  std::vector<LinkPose> poses;
  std::vector<HealthSpan> health;  ///< In time order, from the first pose to the last.
  std::uint64_t frames = 0;        ///< frames with a valid checksum
  std::uint64_t crc_errors = 0;
  std::uint64_t health_texts = 0;  ///< STATUSTEXTs that announce a health
};

/// Decodes a link recording held in memory. Never throws on bad bytes: what does not decode is
/// counted by the parser and skipped.
LinkLog parse_link_log(const std::vector<std::uint8_t>& bytes);

/// Reads and decodes a link file. Throws ReportError ("PATH: reason") when it cannot be read or
/// holds no ODOMETRY.
LinkLog read_link_log(const std::string& path);

/// Short lower-case name of a health for plots and tables ("nominal", "odometry only", ...).
const char* health_label(firmware::Health health);

}  // namespace harmoloc::sim_host
