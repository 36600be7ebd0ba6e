// The config's [link] section and the MAVLink signing key it names.
#include "config_checker.hpp"

#include <filesystem>

#include "harmoloc/drivers/input_file.hpp"

namespace harmoloc::firmware::config_detail {

// Reads a MAVLink signing key: exactly 32 raw bytes, or 64 hex digits (surrounding whitespace
// allowed). Returns an empty string on success, else what is wrong.
std::string read_signing_key(const std::string& path, std::array<std::uint8_t, 32>& key) {
  // A regular file only, opened non-blocking: a FIFO or a terminal could block start-up.
  std::string bytes;
  if (const std::string e =
          drivers::read_regular_file(path, drivers::input_limits::kKeyBytes, bytes);
      !e.empty()) {
    return path + ": " + e;
  }
  const std::string what = path + ": must hold a 32-byte key, raw or as 64 hex digits";
  if (bytes.size() == key.size()) {
    for (std::size_t i = 0; i < key.size(); ++i) key[i] = static_cast<std::uint8_t>(bytes[i]);
  } else {
    const auto space = [](char ch) { return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r'; };
    std::size_t b = 0, e = bytes.size();
    while (b < e && space(bytes[b])) ++b;
    while (e > b && space(bytes[e - 1])) --e;
    if (e - b != 2 * key.size()) return what;
    const auto nibble = [](char ch) -> int {
      if (ch >= '0' && ch <= '9') return ch - '0';
      if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
      if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
      return -1;
    };
    for (std::size_t i = 0; i < key.size(); ++i) {
      const int hi = nibble(bytes[b + 2 * i]);
      const int lo = nibble(bytes[b + 2 * i + 1]);
      if (hi < 0 || lo < 0) return what;
      key[i] = static_cast<std::uint8_t>(hi * 16 + lo);
    }
  }
  bool all_zero = true;
  for (const std::uint8_t v : key) all_zero = all_zero && v == 0;
  if (all_zero) return path + ": the key is all zeros";
  return {};
}

// [link]: MAVLink ids, rate, accepted senders and signing. Relative key and state paths are
// taken from the folder of the config file at @p path.
void read_link(const Checker& check, const toml::table& root, const std::string& path,
               FirmwareConfig& c) {
  if (const toml::table* t = check.section(root, "link")) {
    check.only(*t, "link.",
               {"system_id", "component_id", "baud", "heartbeat_hz", "accept_system_ids",
                "accept_component_ids", "signing_key_file", "signing_state_file",
                "signing_max_ahead_s", "signing_clock", "link_id", "device"});
    c.link.system_id = static_cast<std::uint8_t>(
        check.integer(*t, "system_id", "link.", c.link.system_id, 1, 255));
    c.link.component_id = static_cast<std::uint8_t>(
        check.integer(*t, "component_id", "link.", c.link.component_id, 1, 255));
    c.link.baud =
        static_cast<unsigned>(check.integer(*t, "baud", "link.", c.link.baud, 9600, 921600));
    c.link.heartbeat_hz = check.number(*t, "heartbeat_hz", "link.", c.link.heartbeat_hz, 0.1, 50.0);
    const auto id_list = [&](const char* key, std::vector<std::uint8_t>& ids) {
      const toml::node* n = t->get(key);
      if (n == nullptr) return;
      const toml::array* a = n->as_array();
      if (a == nullptr) check.fail(n, std::string("link.") + key + " must be a list of ids 1..255");
      ids.clear();
      for (const toml::node& e : *a) {
        const auto v = e.value_exact<std::int64_t>();
        if (!v || *v < 1 || *v > 255)
          check.fail(&e, std::string("link.") + key + " must be a list of ids 1..255");
        ids.push_back(static_cast<std::uint8_t>(*v));
      }
    };
    id_list("accept_system_ids", c.link.accept_system_ids);
    id_list("accept_component_ids", c.link.accept_component_ids);
    c.link.link_id =
        static_cast<std::uint8_t>(check.integer(*t, "link_id", "link.", c.link.link_id, 0, 255));
    c.link.signing_key_file = check.text(*t, "signing_key_file", "link.", "");
    if (!c.link.signing_key_file.empty()) {
      // A relative path is taken from the config file's folder, wherever harmoloc is started.
      std::filesystem::path key_path(c.link.signing_key_file);
      if (key_path.is_relative()) key_path = std::filesystem::path(path).parent_path() / key_path;
      const std::string e = read_signing_key(key_path.string(), c.link.signing_key);
      if (!e.empty()) check.fail(t->get("signing_key_file"), "link.signing_key_file: " + e);
      c.link.has_signing_key = true;
    }
    const std::string state = check.text(*t, "signing_state_file", "link.", "");
    if (!state.empty()) {
      std::filesystem::path state_path(state);
      if (state_path.is_relative())
        state_path = std::filesystem::path(path).parent_path() / state_path;
      c.link.signing_state_file = state_path.string();
    }
    // Without it, a signed command captured on the line could be replayed after a restart.
    if (c.link.has_signing_key && c.link.signing_state_file.empty()) {
      check.fail(t->get("signing_key_file"),
                 "link.signing_key_file needs link.signing_state_file (where the replay "
                 "protection survives a restart, e.g. /var/lib/harmoloc/signing.state)");
    }
    c.link.signing_max_ahead_s =
        check.number(*t, "signing_max_ahead_s", "link.", c.link.signing_max_ahead_s, 1.0, 86400.0);
    const std::string clock = check.text(*t, "signing_clock", "link.", "wall");
    if (clock == "wall")
      c.link.signing_peer_clock = false;
    else if (clock == "peer")
      c.link.signing_peer_clock = true;
    else
      check.fail(t->get("signing_clock"), "link.signing_clock must be \"wall\" or \"peer\"");
  }
}

}  // namespace harmoloc::firmware::config_detail
