#pragma once

// What the config reader's parts share (firmware/src/config*.cpp): the checker that turns every
// wrong key, type or range into one line naming the file and line, and the section readers.
// Start-up only.

#include <array>
#include <cstdint>
#include <initializer_list>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include <toml++/toml.h>

#include "harmoloc/firmware/config.hpp"

namespace harmoloc::firmware::config_detail {

class Checker {
 public:
  explicit Checker(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const toml::node* at, const std::string& what) const {
    std::ostringstream s;
    s << file_ << ": ";
    if (at != nullptr && at->source().begin.line > 0)
      s << "line " << at->source().begin.line << ": ";
    s << what;
    throw std::runtime_error(s.str());
  }

  // Rejects keys the firmware does not know (a typo must not silently fall back to a default).
  void only(const toml::table& t, const std::string& where,
            std::initializer_list<const char*> keys) const {
    const std::set<std::string> allowed(keys.begin(), keys.end());
    for (const auto& [key, node] : t) {
      if (allowed.count(std::string(key.str())) == 0) {
        fail(&node, "unknown key '" + where + std::string(key.str()) + "'");
      }
    }
  }

  double number(const toml::table& t, const char* key, const std::string& where, double fallback,
                double lo, double hi) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    double v = 0.0;
    if (auto i = n->value_exact<std::int64_t>())
      v = static_cast<double>(*i);
    else if (auto d = n->value_exact<double>())
      v = *d;
    else
      fail(n, where + key + " must be a number");
    if (!(v >= lo && v <= hi)) {
      std::ostringstream s;
      s << where << key << " = " << v << " is outside " << lo << ".." << hi;
      fail(n, s.str());
    }
    return v;
  }

  // A number in [lo, hi], or the string "auto" (returned as -1: derived from the map).
  double number_or_auto(const toml::table& t, const char* key, const std::string& where,
                        double fallback, double lo, double hi) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    if (auto s = n->value_exact<std::string>()) {
      if (*s == "auto") return -1.0;
      fail(n, where + key + " must be a number or \"auto\"");
    }
    return number(t, key, where, fallback, lo, hi);
  }

  std::int64_t integer(const toml::table& t, const char* key, const std::string& where,
                       std::int64_t fallback, std::int64_t lo, std::int64_t hi) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    auto i = n->value_exact<std::int64_t>();
    if (!i) fail(n, where + key + " must be a whole number");
    if (*i < lo || *i > hi) {
      fail(n, where + key + " = " + std::to_string(*i) + " is outside " + std::to_string(lo) +
                  ".." + std::to_string(hi));
    }
    return *i;
  }

  std::string text(const toml::table& t, const char* key, const std::string& where,
                   const std::string& fallback) const {
    const toml::node* n = t.get(key);
    if (n == nullptr) return fallback;
    auto s = n->value_exact<std::string>();
    if (!s) fail(n, where + key + " must be a string");
    return *s;
  }

  const toml::table* section(const toml::table& root, const char* name) const {
    const toml::node* n = root.get(name);
    if (n == nullptr) return nullptr;
    if (!n->is_table()) fail(n, std::string("[") + name + "] must be a table");
    return n->as_table();
  }

 private:
  std::string file_;
};

inline bool flag(const Checker& check, const toml::table& t, const char* key,
                 const std::string& where, bool fallback) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return fallback;
  auto b = n->value_exact<bool>();
  if (!b) check.fail(n, where + key + " must be true or false");
  return *b;
}

// A switch that takes true, false or "auto" (the map decides): @p on, @p off or @p automatic;
// @p fallback when the key is absent.
template <typename Mode>
Mode on_off_auto(const Checker& check, const toml::table& t, const char* key,
                 const std::string& where, Mode fallback, Mode on, Mode off, Mode automatic) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return fallback;
  if (const auto b = n->value_exact<bool>()) return *b ? on : off;
  const auto text = n->value_exact<std::string>();
  if (!text || *text != "auto") check.fail(n, where + key + " must be true, false or \"auto\"");
  return automatic;
}

// Each reads its section (if present) into @p c, or throws through @p check.
void read_cycle(const Checker& check, const toml::table& root, FirmwareConfig& c);
void read_boards(const Checker& check, const toml::table& root, FirmwareConfig& c);
void read_odometry(const Checker& check, const toml::table& root, FirmwareConfig& c);
void read_can(const Checker& check, const toml::table& root, FirmwareConfig& c);
void read_filter(const Checker& check, const toml::table& root, FirmwareConfig& c);
void read_observation(const Checker& check, const toml::table& root, ObservationConfig& o);
void read_kidnap(const Checker& check, const toml::table& root, KidnapConfig& k);
void read_realtime(const Checker& check, const toml::table& root, FirmwareConfig& c);
void read_link(const Checker& check, const toml::table& root, const std::string& path,
               FirmwareConfig& c);
// The Linux board's devices: [camera], [encoders], link.device (docs/drivers.md).
void read_device_sections(const Checker& check, const toml::table& root, FirmwareConfig& c);
// A MAVLink signing key: exactly 32 raw bytes, or 64 hex digits; "" or what is wrong.
std::string read_signing_key(const std::string& path, std::array<std::uint8_t, 32>& key);

}  // namespace harmoloc::firmware::config_detail
