#pragma once
/// @file What the pieces of harmoloc-sweep (harmoloc_sweep.cpp, sweep_figures.cpp,
/// sweep_output.cpp) share: the figures of the summary and their distributions over scenes, and
/// the writers of sweep.json and index.html. Private to sim_host/tools.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sweep_eval.hpp"

namespace sweep_detail {

using harmoloc::sim_host::SceneResult;

// One figure of the summary: how to read it off a scene, its unit, its targets.
struct Figure {
  std::string key, title, unit;
  std::function<double(const SceneResult&)> value;   // < 0: not measured
  double target_median = -1.0, target_worst = -1.0;  // <= these; -1: none
  bool higher_is_better = false;
};

inline double cm2(double m2) {
  return m2 < 0.0 ? -1.0 : m2 * 1e4;
}
inline double cm(double m) {
  return m < 0.0 ? -1.0 : m * 100.0;
}

// sweep_figures.cpp
std::vector<Figure> figures();

// What the scenes add up to.
struct Totals {
  std::size_t kidnaps = 0, recovered = 0, alarms = 0, failed = 0;
  std::size_t floor_kidnaps = 0, floor_recovered = 0;
  double minutes = 0.0;
};
Totals totals_of(const std::vector<SceneResult>& results);

struct Distribution {
  std::size_t n = 0;
  double median = 0, p90 = 0, worst = 0;
  std::vector<std::uint64_t> worst_seeds;  // up to 3, worst first
};
Distribution distribution(const std::vector<SceneResult>& results, const Figure& f);

// sweep_output.cpp
nlohmann::json to_json(const SceneResult& r);
std::string fmt(double v, int decimals = 2);
void write_html(const std::string& path, const std::vector<SceneResult>& results,
                const SceneResult* reference, const std::string& command);

}  // namespace sweep_detail
