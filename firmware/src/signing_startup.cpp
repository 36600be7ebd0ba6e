#include "harmoloc/firmware/signing_startup.hpp"

#include <array>
#include <cerrno>
#include <filesystem>

#include "harmoloc/drivers/input_file.hpp"
#include "harmoloc/drivers/record_file.hpp"

namespace harmoloc::firmware {

std::string write_signing_state(const LinkConfig& link, const mavlink::SigningState& state) {
  std::array<char, hal::PersistentRecord::kMaxBytes> text{};
  const std::size_t n = mavlink::format_signing_state(state, text.data(), text.size());
  if (n == 0) return "link.signing_state_file " + link.signing_state_file + ": state too large";
  const std::string e = drivers::RecordFile::write_now(
      link.signing_state_file, reinterpret_cast<const std::uint8_t*>(text.data()), n);
  if (!e.empty()) return "link.signing_state_file: " + e;
  return {};
}

std::string start_signing_state(const LinkConfig& link, std::uint64_t signing_now,
                                SigningStartup& out) {
  out = SigningStartup{};
  const std::string& path = link.signing_state_file;
  std::error_code ec;
  if (std::filesystem::symlink_status(path, ec).type() != std::filesystem::file_type::not_found) {
    std::string text;
    if (const std::string e =
            drivers::read_regular_file(path, drivers::input_limits::kStateBytes, text);
        !e.empty()) {
      return "link.signing_state_file " + path + ": " + e;
    }
    if (const std::string e = mavlink::parse_signing_state(text, out.restored); !e.empty()) {
      // Not guessed at: a damaged file could let old commands through. Removing it is the
      // operator's decision (docs/wire-protocol.md).
      return "link.signing_state_file " + path + ": " + e;
    }
  }
  mavlink::SigningState first = out.restored;
  std::uint64_t base = out.restored.high_water;
  if (!link.signing_peer_clock && signing_now > base) base = signing_now;
  const auto lead = static_cast<std::uint64_t>(
      link.signing_max_ahead_s * static_cast<double>(mavlink::kSigningUnitsPerSecond));
  first.high_water = base + lead + mavlink::kPersistReserve;
  if (first.high_water > mavlink::kMaxSigningTimestamp)
    first.high_water = mavlink::kMaxSigningTimestamp;
  if (const std::string e = write_signing_state(link, first); !e.empty()) return e;
  out.durable = first.high_water;
  return {};
}

}  // namespace harmoloc::firmware
