#pragma once
/// @file What came in on the link, counted by mavlink::CommandReceiver (docs/stats-format.md,
/// "inbound"). Apart so the stats file's definition (stats_document.hpp) needs no MAVLink code.

#include <cstdint>

namespace harmoloc::firmware::mavlink {

struct InboundCounters {
  std::uint64_t bytes_in = 0;
  std::uint64_t frames_in = 0;          ///< frames with a valid checksum
  std::uint64_t crc_errors = 0;         ///< candidate frames whose checksum failed
  std::uint64_t bad_headers = 0;        ///< start bytes followed by a header that cannot be checked
  std::uint64_t garbage_bytes = 0;      ///< bytes dropped outside valid frames
  std::uint64_t commands_accepted = 0;  ///< acted on, ACKed MAV_RESULT_ACCEPTED
  std::uint64_t commands_refused = 0;   ///< ACKed with another result (denied, unsupported, ...)
  std::uint64_t rejected_unsigned = 0;  ///< a key is configured and the command was not signed
  std::uint64_t rejected_bad_signature = 0;
  std::uint64_t rejected_replay = 0;
  /// Signed and valid, but dated too far ahead of the signing clock, or beyond the persisted
  /// high-water mark yet (docs/wire-protocol.md, "Signing").
  std::uint64_t rejected_future = 0;
  std::uint64_t rejected_source = 0;   ///< from a system or component not accepted
  std::uint64_t ignored_messages = 0;  ///< valid frames that are not a command for us
  /// TIMESYNC requests that passed the checks (at most one a cycle is answered: the latest).
  std::uint64_t timesync_requests = 0;
  std::uint64_t saturated_cycles = 0;  ///< cycles that stopped at a per-cycle limit
};

}  // namespace harmoloc::firmware::mavlink
