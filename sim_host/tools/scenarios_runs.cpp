// harmoloc-scenarios' runs: the filter variants' configurations and names, running the jobs on
// threads, and the error plots.
#include <algorithm>
#include <cstdio>
#include <mutex>
#include <thread>

#include "harmoloc/sim_host/line_chart.hpp"
#include "scenarios_parts.hpp"

namespace scenarios_detail {

namespace {

firmware::FirmwareConfig config_for(Variant v) {
  firmware::FirmwareConfig c = firmware::default_config();
  switch (v) {
    case Variant::kRobust:
      break;
    case Variant::kNonRobust:
      c.observation.boards.robust = false;
      break;
    case Variant::kFix:
      c.observation.model = firmware::ObservationModel::kFix;
      break;
    case Variant::kUniformReseed:
      c.kidnap.reseed = firmware::ReseedStrategy::kUniform;
      break;
  }
  return c;
}

}  // namespace

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

const char* variant_name(Variant v) {
  switch (v) {
    case Variant::kRobust:
      return "robust per-board (default)";
    case Variant::kNonRobust:
      return "per-board, not robust (Guo & Li 2013)";
    case Variant::kFix:
      return "Gaussian around the harmonic fix";
    case Variant::kUniformReseed:
      return "uniform re-seed (AMCL-style)";
  }
  return "";
}

// Runs the jobs on @p threads threads (each job renders its own frames).
void run_jobs(std::vector<Job>& jobs, const algorithms::MapFile& map, unsigned threads,
              bool quiet) {
  std::mutex m;
  std::size_t next = 0;
  const auto worker = [&]() {
    for (;;) {
      std::size_t i = 0;
      {
        std::lock_guard<std::mutex> lock(m);
        if (next >= jobs.size()) return;
        i = next++;
        if (!quiet) std::fprintf(stderr, "  running %s\n", jobs[i].label.c_str());
      }
      jobs[i].result = sim_host::replay_scenario(jobs[i].scenario, jobs[i].seed, map,
                                                 config_for(jobs[i].variant));
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < std::max(1U, threads); ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
}

const char* short_name(Variant v) {
  switch (v) {
    case Variant::kRobust:
      return "robust";
    case Variant::kNonRobust:
      return "not robust";
    case Variant::kFix:
      return "harmonic fix";
    case Variant::kUniformReseed:
      return "uniform re-seed";
  }
  return "";
}

// Position error against time for several variants of one scenario, as SVG.
std::string error_plot(const std::string& title, const std::vector<const Job*>& jobs,
                       double bound_m, const std::vector<sim_host::Span>& spans) {
  static const char* kColours[] = {"#2ca02c", "#d62728", "#1f77b4", "#ff7f0e"};
  std::vector<double> x;
  std::vector<sim_host::Series> series;
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    sim_host::Series s{short_name(jobs[j]->variant), kColours[j % 4], {}};
    std::vector<double> xs;
    for (const auto& f : jobs[j]->result.frames) {
      if (!f.valid) continue;
      xs.push_back(f.t_s);
      s.y.push_back(std::min(100.0 * f.position_error_m(), 100.0));  // clip at 1 m
    }
    if (x.empty() || xs.size() < x.size()) x = xs;
    series.push_back(std::move(s));
  }
  for (auto& s : series) s.y.resize(std::min(s.y.size(), x.size()));
  return sim_host::line_chart(title, "time, s", "position error, cm (clipped at 100)", x, series,
                              100.0 * bound_m, "bound " + fmt("%.0f cm", 100.0 * bound_m), false,
                              spans);
}

}  // namespace scenarios_detail
