#include "harmoloc/firmware/mavlink_signing.hpp"

#include <nettle/sha2.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "harmoloc/firmware/mavlink_v2.hpp"

namespace harmoloc::firmware::mavlink {

namespace {

std::uint64_t read_u48(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 5; i >= 0; --i) v = (v << 8U) | p[i];
  return v;
}

}  // namespace

std::array<std::uint8_t, kSignatureHashBytes> signature_hash(const SigningKey& key,
                                                             const std::uint8_t* bytes,
                                                             std::size_t size) {
  sha256_ctx ctx;
  sha256_init(&ctx);
  sha256_update(&ctx, key.size(), key.data());
  sha256_update(&ctx, size, bytes);
  std::array<std::uint8_t, SHA256_DIGEST_SIZE> digest{};
  sha256_digest(&ctx, digest.size(), digest.data());
  std::array<std::uint8_t, kSignatureHashBytes> out{};
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = digest[i];
  return out;
}

void Signer::configure(const SigningKey& key, std::uint8_t link_id, const SigningOptions& options) {
  key_ = key;
  link_id_ = link_id;
  options_ = options;
  enabled_ = true;
  synced_ = !options.peer_clock;
}

void Signer::restore(const SigningState& state) {
  floor_ = state.high_water < kMaxSigningTimestamp ? state.high_water : kMaxSigningTimestamp;
  if (floor_ > durable_) durable_ = floor_;
  if (floor_ > last_) last_ = floor_;
  for (std::size_t i = 0; i < state.stream_count && i < streams_.size(); ++i) {
    Stream& s = streams_[i];
    s = Stream{};
    s.used = true;
    s.system_id = state.streams[i].system_id;
    s.component_id = state.streams[i].component_id;
    s.link_id = state.streams[i].link_id;
    s.timestamp = state.streams[i].timestamp;
    s.last_use = ++uses_;
  }
}

bool Signer::persist_due(std::uint64_t now_ns) const {
  if (!enabled_ || !options_.persistent) return false;
  if (offered_ && now_ns - offered_ns_ < kPersistMinIntervalNs) return false;
  return durable_ < now() + options_.max_ahead + kPersistRenewBelow || wanted_ > durable_;
}

SigningState Signer::snapshot(std::uint64_t now_ns) {
  SigningState s;
  std::uint64_t h = now() + options_.max_ahead + kPersistReserve;
  if (wanted_ > h) h = wanted_;
  s.high_water = h < kMaxSigningTimestamp ? h : kMaxSigningTimestamp;
  for (const Stream& st : streams_) {
    if (!st.used) continue;
    s.streams[s.stream_count++] =
        SigningState::Stream{st.timestamp, st.system_id, st.component_id, st.link_id};
  }
  offered_ = true;
  offered_ns_ = now_ns;
  return s;
}

SigningState Signer::final_state() const {
  SigningState s;
  s.high_water = last_ > floor_ ? last_ : floor_;
  for (const Stream& st : streams_) {
    if (!st.used) continue;
    s.streams[s.stream_count++] =
        SigningState::Stream{st.timestamp, st.system_id, st.component_id, st.link_id};
  }
  return s;
}

void Signer::set_time(std::uint64_t timestamp, std::uint64_t now_ns) {
  anchored_ = true;
  anchor_timestamp_ = timestamp < kMaxSigningTimestamp ? timestamp : kMaxSigningTimestamp;
  anchor_ns_ = now_ns;
  clock_ = anchor_timestamp_;
}

void Signer::advance(std::uint64_t now_ns) {
  now_ns_ = now_ns;
  if (!anchored_) {
    // Elapsed time from the first reading: the clock still moves between peers' frames.
    anchored_ = true;
    anchor_timestamp_ = 0;
    anchor_ns_ = now_ns;
  }
  const std::uint64_t elapsed = now_ns > anchor_ns_ ? (now_ns - anchor_ns_) / 10000U : 0U;
  const std::uint64_t t = anchor_timestamp_ + elapsed;
  clock_ = t < kMaxSigningTimestamp ? t : kMaxSigningTimestamp;
}

std::size_t Signer::sign(std::uint8_t* frame, std::size_t size) {
  // Strictly increasing, so that a receiver's replay check never drops two frames of one cycle.
  std::uint64_t t = clock_ > last_ ? clock_ : last_ + 1U;
  if (t > kMaxSigningTimestamp) t = kMaxSigningTimestamp;
  last_ = t;
  std::uint8_t* block = frame + size;
  block[0] = link_id_;
  for (int i = 0; i < 6; ++i) block[1 + i] = static_cast<std::uint8_t>(t >> (8 * i));
  const auto hash = signature_hash(key_, frame, size + 7U);
  for (std::size_t i = 0; i < hash.size(); ++i) block[7 + i] = hash[i];
  return kSignatureBytes;
}

SignatureCheck Signer::verify(const std::uint8_t* frame, std::size_t size) {
  if (size < kHeaderBytes + 1U + kChecksumBytes + kSignatureBytes ||
      (frame[2] & kIncompatSigned) == 0)
    return SignatureCheck::kUnsigned;
  const std::uint8_t* block = frame + size - kSignatureBytes;
  const auto hash = signature_hash(key_, frame, size - kSignatureHashBytes);
  // Compared without an early exit: the time taken says nothing about how much matched.
  std::uint8_t diff = 0;
  for (std::size_t i = 0; i < hash.size(); ++i)
    diff = static_cast<std::uint8_t>(diff | (hash[i] ^ block[7 + i]));
  if (diff != 0) return SignatureCheck::kBadSignature;

  const std::uint8_t system_id = frame[5];
  const std::uint8_t component_id = frame[6];
  const std::uint8_t link_id = block[0];
  const std::uint64_t timestamp = read_u48(block + 1);
  // Persisted by the previous run: whatever it accepted is at or below this.
  if (timestamp <= floor_) return SignatureCheck::kReplay;
  Stream* stream = nullptr;
  Stream* oldest = &streams_[0];
  for (Stream& s : streams_) {
    if (s.used && s.system_id == system_id && s.component_id == component_id &&
        s.link_id == link_id) {
      stream = &s;
      break;
    }
    if (!s.used || (oldest->used && s.last_use < oldest->last_use)) oldest = &s;
  }
  if (stream != nullptr && timestamp <= stream->timestamp) return SignatureCheck::kReplay;
  if (stream == nullptr && timestamp + kReplayWindow < now()) return SignatureCheck::kReplay;
  // Dated too far ahead: a peer's clock gone wrong (or a frame made to push ours forward for
  // good). Not taken, and the clock does not move. A board without a clock (peer_clock) has no
  // bound until the first frame it accepts sets its clock.
  if (synced_ && timestamp > now() + options_.max_ahead) return SignatureCheck::kTooFarAhead;
  if (options_.persistent && timestamp > durable_) {
    // Not covered by the persisted high-water mark yet: taken once it is (the cycle renews it
    // at once; a peer repeats an unanswered command), so that a crash in between cannot let
    // this frame be replayed after the restart.
    const std::uint64_t need = timestamp + options_.max_ahead + kPersistReserve;
    if (need > wanted_) wanted_ = need < kMaxSigningTimestamp ? need : kMaxSigningTimestamp;
    return SignatureCheck::kTooFarAhead;
  }
  if (stream == nullptr) {
    stream = oldest;
    *stream = Stream{};
    stream->used = true;
    stream->system_id = system_id;
    stream->component_id = component_id;
    stream->link_id = link_id;
  }
  stream->timestamp = timestamp;
  stream->last_use = ++uses_;
  if (timestamp > last_) last_ = timestamp;
  if (!synced_) {
    // A board without a clock: the first frame accepted sets it, and runs on from there.
    synced_ = true;
    anchored_ = true;
    anchor_timestamp_ = timestamp;
    anchor_ns_ = now_ns_;
    clock_ = timestamp;
  }
  return SignatureCheck::kAccepted;
}

std::size_t format_signing_state(const SigningState& state, char* out, std::size_t size) {
  std::size_t n = 0;
  const auto put = [&](int written) {
    if (written < 0 || static_cast<std::size_t>(written) >= size - n) return false;
    n += static_cast<std::size_t>(written);
    return true;
  };
  if (size == 0) return 0;
  if (!put(std::snprintf(out, size, "harmoloc-signing-state 1\nhigh_water %llu\n",
                         static_cast<unsigned long long>(state.high_water)))) {
    return 0;
  }
  for (std::size_t i = 0; i < state.stream_count && i < state.streams.size(); ++i) {
    const SigningState::Stream& s = state.streams[i];
    if (!put(std::snprintf(out + n, size - n, "stream %u %u %u %llu\n", unsigned{s.system_id},
                           unsigned{s.component_id}, unsigned{s.link_id},
                           static_cast<unsigned long long>(s.timestamp)))) {
      return 0;
    }
  }
  return n;
}

namespace {

// Reads the whole decimal number @p field into @p value (at most @p max).
bool read_number(std::string_view field, std::uint64_t max, std::uint64_t& value) {
  if (field.empty() || field.size() > 20) return false;
  value = 0;
  for (const char c : field) {
    if (c < '0' || c > '9') return false;
    const auto d = static_cast<std::uint64_t>(c - '0');
    if (value > (max - d) / 10U) return false;
    value = value * 10U + d;
  }
  return true;
}

}  // namespace

std::string parse_signing_state(std::string_view text, SigningState& state) {
  state = SigningState{};
  std::size_t line_no = 0, pos = 0;
  bool have_header = false, have_high_water = false;
  while (pos < text.size()) {
    const std::size_t eol = text.find('\n', pos);
    const std::string_view line =
        text.substr(pos, eol == std::string_view::npos ? std::string_view::npos : eol - pos);
    pos = eol == std::string_view::npos ? text.size() : eol + 1;
    ++line_no;
    const std::string at = "line " + std::to_string(line_no) + ": ";
    // Space-separated fields.
    std::string_view fields[6];
    std::size_t count = 0, i = 0;
    while (i < line.size()) {
      while (i < line.size() && line[i] == ' ') ++i;
      if (i >= line.size()) break;
      const std::size_t end = line.find(' ', i);
      const std::size_t stop = end == std::string_view::npos ? line.size() : end;
      if (count == 6) return at + "too many fields";
      fields[count++] = line.substr(i, stop - i);
      i = stop;
    }
    if (!have_header) {
      if (count != 2 || fields[0] != "harmoloc-signing-state" || fields[1] != "1")
        return at + "not a harmoloc signing state (expected 'harmoloc-signing-state 1')";
      have_header = true;
      continue;
    }
    if (count == 0) continue;
    std::uint64_t v[4] = {0, 0, 0, 0};
    if (fields[0] == "high_water" && count == 2) {
      if (have_high_water) return at + "a second high_water";
      if (!read_number(fields[1], kMaxSigningTimestamp, v[0]))
        return at + "high_water must be a timestamp (0..2^48-1)";
      state.high_water = v[0];
      have_high_water = true;
    } else if (fields[0] == "stream" && count == 5) {
      if (!read_number(fields[1], 255, v[0]) || !read_number(fields[2], 255, v[1]) ||
          !read_number(fields[3], 255, v[2]) || !read_number(fields[4], kMaxSigningTimestamp, v[3]))
        return at + "expected 'stream SYSTEM COMPONENT LINK TIMESTAMP'";
      if (state.stream_count == state.streams.size()) return at + "more than 32 streams";
      state.streams[state.stream_count++] =
          SigningState::Stream{v[3], static_cast<std::uint8_t>(v[0]),
                               static_cast<std::uint8_t>(v[1]), static_cast<std::uint8_t>(v[2])};
    } else {
      return at + "expected 'high_water T' or 'stream SYSTEM COMPONENT LINK T'";
    }
  }
  if (!have_header) return "line 1: empty (expected 'harmoloc-signing-state 1')";
  if (!have_high_water) return "no high_water line";
  for (std::size_t k = 0; k < state.stream_count; ++k) {
    if (state.streams[k].timestamp > state.high_water)
      return "a stream's timestamp is above high_water";
  }
  return {};
}

}  // namespace harmoloc::firmware::mavlink
