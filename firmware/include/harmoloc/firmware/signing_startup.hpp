#pragma once
/// @file The MAVLink signing state across restarts, at start-up and at a clean stop (both board
/// mains): the state file is read and checked, the run's first high-water mark is on storage
/// before the first cycle, and a clean stop leaves the highest timestamp used
/// (docs/wire-protocol.md, "Signing").

#include <cstdint>
#include <string>

#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/mavlink_signing.hpp"

namespace harmoloc::firmware {

struct SigningStartup {
  mavlink::SigningState restored;  ///< what the previous run persisted (all zero: a first start)
  std::uint64_t durable = 0;       ///< the high-water mark now on storage
};

/// Reads link.signing_state_file (missing: a first start), then writes the state the run starts
/// with: its high-water mark above the later of the persisted one and @p signing_now (the wall
/// time in signing units; ignored with link.signing_clock = "peer"), plus the allowed lead and
/// the reserve. Returns an empty string, or one line naming the file.
std::string start_signing_state(const LinkConfig& link, std::uint64_t signing_now,
                                SigningStartup& out);

/// Writes @p state to link.signing_state_file now (a clean stop). Returns "" or one line.
std::string write_signing_state(const LinkConfig& link, const mavlink::SigningState& state);

}  // namespace harmoloc::firmware
