#pragma once
/// @file A small record that must survive a restart (the MAVLink signing clock and streams),
/// written without ever blocking the cycle: the cycle hands a record over, someone else (a
/// thread, on Linux) writes it to storage, and the cycle learns which record is there by its tag.

#include <cstddef>
#include <cstdint>

namespace harmoloc::hal {

class PersistentRecord {
 public:
  /// The largest record that may be handed over.
  static constexpr std::size_t kMaxBytes = 4096;

  /// Hands over @p size bytes (at most kMaxBytes) tagged @p tag (rising from one record to the
  /// next) to be written in place of the previous record. Never blocks: false when a record is
  /// still being handed over or the store has failed (try again later).
  virtual bool offer(const std::uint8_t* bytes, std::size_t size, std::uint64_t tag) = 0;
  /// The tag of the newest record known to be on storage (0: none yet).
  virtual std::uint64_t durable_tag() const = 0;
  /// Writes that failed so far.
  virtual std::uint64_t failures() const = 0;

 protected:
  ~PersistentRecord() = default;
};

}  // namespace harmoloc::hal
