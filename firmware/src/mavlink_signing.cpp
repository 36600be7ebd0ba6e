#include "harmoloc/firmware/mavlink_signing.hpp"

#include <nettle/sha2.h>

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

void Signer::configure(const SigningKey& key, std::uint8_t link_id) {
  key_ = key;
  link_id_ = link_id;
  enabled_ = true;
}

void Signer::set_time(std::uint64_t timestamp, std::uint64_t now_ns) {
  anchored_ = true;
  anchor_timestamp_ = timestamp < kMaxSigningTimestamp ? timestamp : kMaxSigningTimestamp;
  anchor_ns_ = now_ns;
  clock_ = anchor_timestamp_;
}

void Signer::advance(std::uint64_t now_ns) {
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
  if (stream != nullptr) {
    if (timestamp <= stream->timestamp) return SignatureCheck::kReplay;
  } else {
    if (timestamp + kReplayWindow < now()) return SignatureCheck::kReplay;
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
  return SignatureCheck::kAccepted;
}

}  // namespace harmoloc::firmware::mavlink
