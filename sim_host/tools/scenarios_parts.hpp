#pragma once
/// @file What the pieces of harmoloc-scenarios (harmoloc_scenarios.cpp, scenarios_runs.cpp)
/// share: the filter variants the table compares, the runs (jobs) and their plots. Private to
/// sim_host/tools.

#include <cstdint>
#include <string>
#include <vector>

#include "scenario_eval.hpp"

namespace scenarios_detail {

using namespace harmoloc;

std::string fmt(const char* f, double v);

// The filter variants the table compares.
enum class Variant { kRobust, kNonRobust, kFix, kUniformReseed };
const char* variant_name(Variant v);
const char* short_name(Variant v);

struct Job {
  std::string label;
  sim_host::Scenario scenario;
  std::uint64_t seed;
  Variant variant;
  sim_host::RunRecord result;
};

// Runs the jobs on @p threads threads (each job renders its own frames).
void run_jobs(std::vector<Job>& jobs, const algorithms::MapFile& map, unsigned threads, bool quiet);

// Position error against time for several variants of one scenario, as SVG.
std::string error_plot(const std::string& title, const std::vector<const Job*>& jobs,
                       double bound_m, const std::vector<sim_host::Span>& spans);

}  // namespace scenarios_detail
