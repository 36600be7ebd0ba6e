// A scenario file's fields, read and checked: numbers within their ranges, colours, intervals,
// no unknown keys; an error names the file and the key.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "scenario_parts.hpp"

namespace harmoloc::sim_host::scenario_detail {

[[noreturn]] void fail(const std::string& file, const std::string& what) {
  throw std::runtime_error(file + ": " + what);
}

double num(const toml::node& n, const std::string& file, const std::string& key) {
  if (auto i = n.value_exact<std::int64_t>()) return static_cast<double>(*i);
  if (auto d = n.value_exact<double>()) return *d;
  fail(file, key + " must be a number");
}

void set_num(const toml::table& t, const char* key, double& out, const std::string& file,
             const std::string& section, double lo, double hi) {
  if (const toml::node* n = t.get(key)) {
    const double v = num(*n, file, section + key);
    if (!(v >= lo && v <= hi)) {
      std::ostringstream s;
      s << section << key << " = " << v << " is outside " << lo << ".." << hi;
      fail(file, s.str());
    }
    out = v;
  }
}

// A scenario file is checked as strictly as the firmware config: a typo must not fall back to a
// default silently.
void only(const toml::table& t, const std::string& file, const std::string& where,
          std::initializer_list<const char*> keys) {
  for (const auto& [key, node] : t) {
    bool known = false;
    for (const char* k : keys) known = known || key.str() == k;
    if (!known) fail(file, "unknown key '" + where + std::string(key.str()) + "'");
  }
}

std::vector<double> numbers(const toml::node* n, std::size_t count, const std::string& file,
                            const std::string& key) {
  const toml::array* a = n != nullptr ? n->as_array() : nullptr;
  if (a == nullptr || a->size() != count)
    fail(file, key + " must be an array of " + std::to_string(count) + " numbers");
  std::vector<double> out;
  for (const toml::node& e : *a) out.push_back(num(e, file, key));
  return out;
}

// A number that must be present and within lo..hi.
double required_num(const toml::table& t, const char* key, const std::string& file,
                    const std::string& section, double lo, double hi) {
  if (t.get(key) == nullptr) fail(file, section + key + " is required");
  double v = 0.0;
  set_num(t, key, v, file, section, lo, hi);
  return v;
}

Rgb colour_of(const toml::table& t, const std::string& file, const std::string& key) {
  const auto c = numbers(t.get("colour"), 3, file, key);
  for (double v : c) {
    if (!(v >= 0 && v <= 255)) fail(file, key + " values must be 0..255");
  }
  return Rgb{static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]),
             static_cast<std::uint8_t>(c[2])};
}

bool boolean(const toml::table& t, const char* key, bool fallback, const std::string& file,
             const std::string& section) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return fallback;
  const auto v = n->value_exact<bool>();
  if (!v) fail(file, section + key + " must be true or false");
  return *v;
}

// A colour under @p key (not "colour"): [r, g, b], 0..255 each.
void set_colour(const toml::table& t, const char* key, Rgb& out, const std::string& file,
                const std::string& section) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return;
  const auto c = numbers(n, 3, file, section + key);
  for (double v : c) {
    if (!(v >= 0 && v <= 255)) fail(file, section + key + " values must be 0..255");
  }
  out = Rgb{static_cast<std::uint8_t>(c[0]), static_cast<std::uint8_t>(c[1]),
            static_cast<std::uint8_t>(c[2])};
}

// An interval [lo, hi] with lo < hi, both within +-@p bound.
void set_interval(const toml::table& t, const char* key, std::array<double, 2>& out,
                  const std::string& file, const std::string& section, double bound) {
  const toml::node* n = t.get(key);
  if (n == nullptr) return;
  const auto v = numbers(n, 2, file, section + key);
  if (!(std::fabs(v[0]) <= bound && std::fabs(v[1]) <= bound && v[0] < v[1])) {
    std::ostringstream m;
    m << section << key << " must be [min, max] with min < max, within +-" << bound;
    fail(file, m.str());
  }
  out = {v[0], v[1]};
}

}  // namespace harmoloc::sim_host::scenario_detail
