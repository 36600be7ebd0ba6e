#pragma once
/// @file What the pieces of the scenario code (scenario*.cpp) share: the built-in catalogue and
/// the file reader call each other (a file's base is a built-in scenario or another file), and
/// the reader's typed TOML fields. Private to sim_host/src.

#include <array>
#include <cstddef>
#include <initializer_list>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/sim_host/scenario.hpp"

namespace harmoloc::sim_host::scenario_detail {

constexpr double kDeg = algorithms::kPi / 180.0;

// scenario_catalog.cpp: a built-in scenario by name, else a scenario file (@p depth: how many
// files chained by 'base' led here).
Scenario load_scenario_at_depth(const std::string& name_or_file, int depth);

// scenario_file_read.cpp: a scenario file, its base loaded at @p depth + 1.
Scenario from_file(const std::string& file, int depth);

// scenario_toml_fields.cpp: a scenario file's fields, checked (errors name the file).
[[noreturn]] void fail(const std::string& file, const std::string& what);
double num(const toml::node& n, const std::string& file, const std::string& key);
void set_num(const toml::table& t, const char* key, double& out, const std::string& file,
             const std::string& section, double lo, double hi);
void only(const toml::table& t, const std::string& file, const std::string& where,
          std::initializer_list<const char*> keys);
std::vector<double> numbers(const toml::node* n, std::size_t count, const std::string& file,
                            const std::string& key);
double required_num(const toml::table& t, const char* key, const std::string& file,
                    const std::string& section, double lo, double hi);
Rgb colour_of(const toml::table& t, const std::string& file, const std::string& key);
bool boolean(const toml::table& t, const char* key, bool fallback, const std::string& file,
             const std::string& section);
void set_colour(const toml::table& t, const char* key, Rgb& out, const std::string& file,
                const std::string& section);
void set_interval(const toml::table& t, const char* key, std::array<double, 2>& out,
                  const std::string& file, const std::string& section, double bound);

template <typename T>
void set_int(const toml::table& t, const char* key, T& out, const std::string& file,
             const std::string& section, double lo, double hi) {
  double v = static_cast<double>(out);
  set_num(t, key, v, file, section, lo, hi);
  out = static_cast<T>(v);
}

}  // namespace harmoloc::sim_host::scenario_detail
