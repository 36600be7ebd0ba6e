// harmoloc-budget: the timing budget table of a run, from the firmware's stats JSON.
#include <cstdio>
#include <sstream>

#include <CLI/CLI.hpp>

#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/sim_host/run_stats.hpp"

int main(int argc, char** argv) {
  using namespace harmoloc::sim_host;
  CLI::App app{
      "harmoloc-budget: per-stage cycle time against the compute budget, from `harmoloc --stats` "
      "output.\n"
      "Prints median, p99, p99.9 and max of every stage and their share of the budget, the "
      "overruns and,\n"
      "for paced runs (--realtime), the wake-up latency. With --check, exits 1 when the run "
      "overran\n"
      "(with --budget-ms: a cycle took longer than that budget), its whole-cycle p99.9 is above "
      "the\n"
      "budget, or it never produced a pose (its timing then says nothing about a localizing "
      "cycle).",
      "harmoloc-budget"};
  std::string stats_path;
  double budget_ms = 0.0;
  bool check = false;
  app.add_option("stats", stats_path, "stats JSON written by harmoloc --stats")->required();
  app.add_option("--budget-ms", budget_ms,
                 "budget to compare against (default: the one in the stats)");
  app.add_flag("--check", check, "exit 1 if the run does not fit the budget");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  try {
    const RunStats stats = read_stats(stats_path);
    const double budget_us = budget_ms > 0.0 ? budget_ms * 1000.0 : stats.budget_us;
    std::printf("budget %.3g ms per cycle; %s board, %llu cycles at %.0f Hz\n", budget_us / 1000.0,
                stats.board.empty() ? "?" : stats.board.c_str(),
                static_cast<unsigned long long>(stats.cycles.value_or(0)),
                stats.rate_hz.value_or(0.0));
    std::printf("%-10s %10s %10s %10s %10s %12s\n", "stage", "median us", "p99 us", "p99.9 us",
                "max us", "max/budget");
    for (const StageTiming& s : stats.stages) {
      std::printf("%-10s %10.1f %10.1f %10.1f %10.1f %11.2f%%\n", s.name.c_str(), s.median_us,
                  s.p99_us, s.p999_us, s.max_us, 100.0 * s.max_us / budget_us);
    }
    const std::uint64_t overruns = stats.overruns.value_or(0);
    std::printf("overruns   %llu\n", static_cast<unsigned long long>(overruns));
    const harmoloc::firmware::stats::Document& doc = stats.document;
    if (doc.pacing) {
      std::printf("pacing     %s, %llu skipped ticks, %llu overrun alarms\n",
                  doc.pacing->mode.empty() ? "?" : doc.pacing->mode.c_str(),
                  static_cast<unsigned long long>(doc.pacing->skipped_ticks),
                  static_cast<unsigned long long>(doc.pacing->overrun_alarms));
    }
    if (const auto& w = doc.wakeup_latency) {
      std::printf(
          "wake-up    min %.1f us, median %.1f us, p99 %.1f us, p99.9 %.1f us, max %.1f us over "
          "%llu wake-ups\n",
          w->min_us, w->median_us, w->p99_us, w->p999_us, w->max_us,
          static_cast<unsigned long long>(w->count));
    }
    if (const auto& l = doc.capture_to_send) {
      // What an autopilot's vision delay parameter is set from (docs/wire-protocol.md).
      std::printf(
          "latency    capture to send: median %.1f ms, p99 %.1f ms, max %.1f ms over %llu poses\n",
          l->median_us / 1000.0, l->p99_us / 1000.0, l->max_us / 1000.0,
          static_cast<unsigned long long>(l->count));
    }
    // A run whose every cycle was before the first pose never segmented a known place, never
    // updated the filter: its times are not those of a localizing cycle.
    const std::uint64_t without_pose = doc.health_cycles ? doc.health_cycles->not_initialized : 0;
    const std::uint64_t cycles = stats.cycles.value_or(0);
    const bool never_localized = cycles > 0 && without_pose >= cycles;
    std::printf("localised  %s (%llu of %llu cycles without a pose)\n",
                never_localized ? "NEVER" : "yes", static_cast<unsigned long long>(without_pose),
                static_cast<unsigned long long>(cycles));
    const StageTiming* cycle = stats.stage("cycle");
    // The firmware counted its overruns against its own budget; against another one (--budget-ms)
    // no cycle may take longer than that budget instead.
    const bool own_budget = !(budget_ms > 0.0) || budget_us == stats.budget_us;
    const bool fits = cycle != nullptr && cycle->p999_us <= budget_us &&
                      (own_budget ? overruns == 0 : cycle->max_us <= budget_us);
    if (cycle != nullptr) {
      std::printf("verdict    %s: whole cycle p99.9 %.1f us = %.1f%% of the budget, max %.1f%%\n",
                  never_localized ? "NO POSE (timing not representative)"
                  : fits          ? "fits"
                                  : "DOES NOT FIT",
                  cycle->p999_us, 100.0 * cycle->p999_us / budget_us,
                  100.0 * cycle->max_us / budget_us);
    }
    return check && (!fits || never_localized) ? 1 : 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harmoloc-budget: %s\n", e.what());
    return 2;
  }
}
