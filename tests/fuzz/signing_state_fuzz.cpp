// Fuzz target: the MAVLink signing state file (firmware::mavlink::parse_signing_state, read at
// start-up from link.signing_state_file). A parsed state must keep its documented bounds (at most
// 32 streams, every timestamp within 48 bits and not above the high-water mark), format back into
// a record of at most hal::PersistentRecord::kMaxBytes that parses to the same state, and be
// restorable into a Signer whose replay floor then refuses the high-water mark itself.

#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_common.hpp"
#include "harmoloc/firmware/mavlink_signing.hpp"

namespace mv = harmoloc::firmware::mavlink;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  mv::SigningState state;
  const std::string error = mv::parse_signing_state(text, state);
  if (!error.empty()) {
    HARMOLOC_FUZZ_CHECK(error.find('\n') == std::string::npos, "error message of several lines");
    return 0;
  }
  HARMOLOC_FUZZ_CHECK(state.high_water <= mv::kMaxSigningTimestamp, "high_water beyond 48 bits");
  HARMOLOC_FUZZ_CHECK(state.stream_count <= mv::SigningState::kMaxStreams, "too many streams");
  for (std::size_t i = 0; i < state.stream_count; ++i)
    HARMOLOC_FUZZ_CHECK(state.streams[i].timestamp <= state.high_water, "stream above high_water");
  char record[4096];
  const std::size_t n = mv::format_signing_state(state, record, sizeof record);
  HARMOLOC_FUZZ_CHECK(n > 0, "a parsed state does not fit a record");
  mv::SigningState back;
  HARMOLOC_FUZZ_CHECK(mv::parse_signing_state(std::string_view(record, n), back).empty(),
                      "a formatted state does not parse");
  bool same = back.high_water == state.high_water && back.stream_count == state.stream_count;
  for (std::size_t i = 0; same && i < state.stream_count; ++i) {
    const auto& a = state.streams[i];
    const auto& b = back.streams[i];
    same = a.timestamp == b.timestamp && a.system_id == b.system_id &&
           a.component_id == b.component_id && a.link_id == b.link_id;
  }
  HARMOLOC_FUZZ_CHECK(same, "a formatted state parses back different");
  mv::Signer signer;
  signer.configure(mv::SigningKey{1}, 0);
  signer.restore(state);
  HARMOLOC_FUZZ_CHECK(signer.now() >= state.high_water, "the clock starts below the mark");
  return 0;
}
