#pragma once
/// @file MAVLink 2 message signing: a 13-byte block after the checksum (link id, 48-bit
/// timestamp, the first 6 bytes of SHA-256(secret key + frame up to the timestamp)), incompat
/// flag 0x01. SHA-256 is libnettle's (Debian nettle-dev). The Signer signs outbound frames and
/// checks inbound ones: signature, then replay (per sysid/compid/link id stream, the timestamp
/// must rise; a new stream may start at most a minute behind the local signing clock). Fixed
/// tables, no allocation. Wire details in docs/wire-protocol.md.

#include <array>
#include <cstddef>
#include <cstdint>

namespace harmoloc::firmware::mavlink {

using SigningKey = std::array<std::uint8_t, 32>;
constexpr std::size_t kSignatureHashBytes = 6;
/// Signing timestamps count 10 microseconds since 2015-01-01 00:00:00 UTC, in 48 bits.
constexpr std::uint64_t kSigningEpochUnixUs = 1420070400ULL * 1000000ULL;
constexpr std::uint64_t kMaxSigningTimestamp = (1ULL << 48U) - 1U;
/// How far (1 minute) behind the local signing clock a new stream may start.
constexpr std::uint64_t kReplayWindow = 60ULL * 100000ULL;

constexpr std::uint64_t signing_timestamp_from_unix_us(std::uint64_t unix_us) {
  return unix_us > kSigningEpochUnixUs ? (unix_us - kSigningEpochUnixUs) / 10U : 0U;
}

/// SHA-256 of @p key followed by the @p size bytes at @p bytes (a frame from its start byte
/// through the signature's timestamp), cut to its first 6 bytes.
std::array<std::uint8_t, kSignatureHashBytes> signature_hash(const SigningKey& key,
                                                             const std::uint8_t* bytes,
                                                             std::size_t size);

enum class SignatureCheck : std::uint8_t {
  kAccepted = 0,
  kUnsigned = 1,      ///< no signature, or too short to hold one
  kBadSignature = 2,  ///< the hash does not match the key
  kReplay = 3,        ///< valid, but not newer than its stream's last frame, or too old
};

class Signer {
 public:
  /// Streams remembered for replay protection; the least recently used one makes room.
  static constexpr std::size_t kMaxStreams = 32;

  void configure(const SigningKey& key, std::uint8_t link_id);
  bool enabled() const { return enabled_; }
  std::uint8_t link_id() const { return link_id_; }

  /// Anchors the signing clock: at monotonic @p now_ns it reads @p timestamp. Without an anchor
  /// (a board without a real-time clock) it starts at 0 and is carried up by every timestamp
  /// accepted from a peer.
  void set_time(std::uint64_t timestamp, std::uint64_t now_ns);
  /// Moves the clock to monotonic @p now_ns (once a cycle, before anything is signed).
  void advance(std::uint64_t now_ns);
  /// The local signing time: never behind a timestamp sent or accepted.
  std::uint64_t now() const { return clock_ > last_ ? clock_ : last_; }

  /// Appends link id, timestamp and signature to an outbound frame of @p size bytes whose
  /// incompat flag and checksum are already written; @p frame must have room for 13 more bytes.
  /// Returns the bytes appended (kSignatureBytes).
  std::size_t sign(std::uint8_t* frame, std::size_t size);

  /// Checks a whole inbound frame of @p size bytes (signature included when flagged). Only an
  /// accepted frame moves its stream's timestamp and the clock.
  SignatureCheck verify(const std::uint8_t* frame, std::size_t size);

 private:
  struct Stream {
    std::uint64_t timestamp = 0;
    std::uint64_t last_use = 0;
    std::uint8_t system_id = 0;
    std::uint8_t component_id = 0;
    std::uint8_t link_id = 0;
    bool used = false;
  };

  SigningKey key_{};
  bool enabled_ = false;
  std::uint8_t link_id_ = 0;
  bool anchored_ = false;
  std::uint64_t anchor_timestamp_ = 0;
  std::uint64_t anchor_ns_ = 0;
  std::uint64_t clock_ = 0;  ///< the clock's own reading
  std::uint64_t last_ = 0;   ///< highest timestamp sent or accepted
  std::uint64_t uses_ = 0;
  std::array<Stream, kMaxStreams> streams_{};
};

}  // namespace harmoloc::firmware::mavlink
