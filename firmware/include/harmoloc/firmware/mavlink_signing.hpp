#pragma once
/// @file MAVLink 2 message signing: a 13-byte block after the checksum (link id, 48-bit
/// timestamp, the first 6 bytes of SHA-256(secret key + frame up to the timestamp)), incompat
/// flag 0x01. SHA-256 is libnettle's (Debian nettle-dev). The Signer signs outbound frames and
/// checks inbound ones: signature, then replay (per sysid/compid/link id stream, the timestamp
/// must rise; a new stream may start at most a minute behind the local signing clock; nothing
/// at or below the high-water mark persisted by the previous run), then how far ahead of the
/// local clock a frame may be. What must survive a restart (SigningState) is persisted through a
/// hal::PersistentRecord, ahead of need and at a bounded rate. Fixed tables, no allocation.
/// Wire details in docs/wire-protocol.md.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace harmoloc::firmware::mavlink {

using SigningKey = std::array<std::uint8_t, 32>;
constexpr std::size_t kSignatureHashBytes = 6;
/// Signing timestamps count 10 microseconds since 2015-01-01 00:00:00 UTC, in 48 bits.
constexpr std::uint64_t kSigningEpochUnixUs = 1420070400ULL * 1000000ULL;
constexpr std::uint64_t kMaxSigningTimestamp = (1ULL << 48U) - 1U;
/// How far (1 minute) behind the local signing clock a new stream may start.
constexpr std::uint64_t kReplayWindow = 60ULL * 100000ULL;
/// Signing-clock units (10 us) in a second.
constexpr std::uint64_t kSigningUnitsPerSecond = 100000ULL;
/// How far beyond the clock plus the allowed lead the persisted high-water mark is put (60 s),
/// and how little of that is left before it is renewed (30 s): in steady state one write every
/// 30 s, and never more than one a second.
constexpr std::uint64_t kPersistReserve = 60ULL * kSigningUnitsPerSecond;
constexpr std::uint64_t kPersistRenewBelow = 30ULL * kSigningUnitsPerSecond;
constexpr std::uint64_t kPersistMinIntervalNs = 1000000000ULL;

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
  /// Valid, but not newer than its stream's last frame, a new stream too far behind the clock,
  /// or at or below the high-water mark the previous run persisted.
  kReplay = 3,
  /// Valid, but dated further ahead of the local clock than allowed, or beyond what is
  /// persisted yet (accepting it could let it be replayed after a restart).
  kTooFarAhead = 4,
};

/// What the replay protection needs across a restart (the MAVLink 2 signing spec: persist the
/// timestamp; here also the streams' last timestamps).
struct SigningState {
  struct Stream {
    std::uint64_t timestamp = 0;
    std::uint8_t system_id = 0;
    std::uint8_t component_id = 0;
    std::uint8_t link_id = 0;
  };
  static constexpr std::size_t kMaxStreams = 32;
  /// Above every timestamp sent or accepted; after a restart nothing at or below it is accepted
  /// and the clock starts no lower.
  std::uint64_t high_water = 0;
  std::array<Stream, kMaxStreams> streams{};
  std::size_t stream_count = 0;
};

/// Writes @p state as text ("harmoloc-signing-state 1", then "high_water T" and one
/// "stream SYS COMP LINK T" line per stream) into @p out (@p size bytes). Returns the length, or
/// 0 if it does not fit. No allocation.
std::size_t format_signing_state(const SigningState& state, char* out, std::size_t size);

/// Reads the text format_signing_state() writes. Returns an empty string, or "line N: reason".
std::string parse_signing_state(std::string_view text, SigningState& state);

/// How a Signer treats time.
struct SigningOptions {
  /// How far ahead of the local clock a frame's timestamp may be (signing units).
  std::uint64_t max_ahead = 60ULL * kSigningUnitsPerSecond;
  /// A board without a clock: the local clock's time is not trusted until the first signed
  /// frame is accepted (which sets it); until then the lead is not bounded.
  bool peer_clock = false;
  /// Accept only timestamps the persisted high-water mark covers (set_durable()): whatever was
  /// accepted can then never be accepted again after a restart.
  bool persistent = false;
};

class Signer {
 public:
  /// Streams remembered for replay protection; the least recently used one makes room.
  static constexpr std::size_t kMaxStreams = 32;

  void configure(const SigningKey& key, std::uint8_t link_id,
                 const SigningOptions& options = SigningOptions{});
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

  /// Restores what the previous run persisted (start-up, before any frame): nothing at or below
  /// @p state.high_water is accepted, the clock does not start below it, and the streams carry
  /// on from their last timestamps.
  void restore(const SigningState& state);
  /// The newest high-water mark known to be on storage.
  void set_durable(std::uint64_t high_water) {
    if (high_water > durable_) durable_ = high_water;
  }
  std::uint64_t durable() const { return durable_; }
  /// Whether the persisted high-water mark should be renewed now (less than
  /// kPersistRenewBelow left above the clock plus the allowed lead, or a frame above it is
  /// waiting), at most once per kPersistMinIntervalNs of monotonic @p now_ns.
  bool persist_due(std::uint64_t now_ns) const;
  /// The state to persist now: high_water = the clock + the allowed lead + kPersistReserve (or
  /// what a waiting frame needs). Records the time of the offer (@p now_ns).
  SigningState snapshot(std::uint64_t now_ns);
  /// The store refused the last snapshot (its writer held the lock for a moment): the renewal
  /// is due again on the next cycle instead of kPersistMinIntervalNs later.
  void snapshot_refused() { offered_ = false; }
  /// The state to persist at a clean stop: high_water = the highest timestamp sent or accepted,
  /// so that after a restart the peers' current frames are taken at once (after a crash the
  /// last renewal, up to two minutes ahead, is in force instead).
  SigningState final_state() const;

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
  SigningOptions options_{};
  bool enabled_ = false;
  bool synced_ = true;         ///< the clock is trusted (false: peer clock, no frame yet)
  std::uint64_t floor_ = 0;    ///< persisted by the previous run: nothing at or below it
  std::uint64_t durable_ = 0;  ///< on storage now
  std::uint64_t wanted_ = 0;   ///< a high-water mark a frame above durable_ asked for
  std::uint64_t offered_ns_ = 0;
  bool offered_ = false;
  std::uint64_t now_ns_ = 0;  ///< monotonic time of the last advance()
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
