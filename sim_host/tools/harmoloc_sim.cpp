// harmoloc-sim: writes a dataset folder (frames, encoder log, ground truth, labels, metadata)
// for a simulated scenario run.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include <CLI/CLI.hpp>

#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/sim_host/random_scene.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/simulate.hpp"

int main(int argc, char** argv) {
  using namespace harmoloc::sim_host;
  CLI::App app{
      "harmoloc-sim: simulate a scenario run and write it as a dataset folder.\n"
      "The folder holds frames/ (binary PPM), frames.csv, encoders.log (candump -l), "
      "groundtruth.tum,\n"
      "labels.tum (the poses an external reference would label), metadata.toml, scenario.toml\n"
      "and, for a run with kidnaps, kidnaps.csv.\n"
      "--random SEED draws a scene of the random family instead (room, boards, lens, resolution,\n"
      "noise, lighting, robot, route, labels; the same seed gives the same scene) and also writes\n"
      "harmoloc.toml, a firmware config with its boards' colour windows and the robot's geometry.\n"
      "See docs/dataset-format.md and docs/scenarios.md.",
      "harmoloc-sim"};
  std::string scenario_name = "desk-shuttle";
  std::string out_dir;
  std::uint64_t seed = 1;
  std::optional<std::uint64_t> random_seed, run_seed, lighting_seed;
  std::string variant;
  int kidnaps = 10;
  int waypoints = 8;
  std::uint64_t roam_seed = 1;
  double minutes = 10.0;
  bool list = false, quiet = false;
  auto* scenario_opt =
      app.add_option("--scenario", scenario_name, "built-in scenario name or a scenario .toml file")
          ->capture_default_str();
  app.add_option("--random", random_seed,
                 "draw the random scene of this seed (docs/scenarios.md, Random scenes) instead "
                 "of --scenario; writes harmoloc.toml too")
      ->excludes(scenario_opt);
  app.add_option("--variant", variant,
                 "with --random: kidnap (--kidnaps of them), dynamic (a person hides a board, a "
                 "board moves), long (--minutes of driving), coverage (lanes over a floor around "
                 "the route at several headings: a floor map's training run), roam (random poses "
                 "on that floor, --waypoints of them, drawn from --roam-seed: a test run off any "
                 "trained path)")
      ->check(CLI::IsMember({"kidnap", "dynamic", "long", "coverage", "roam"}));
  app.add_option("--run-seed", run_seed,
                 "with --random: the run's seed (pixel noise, slip, wander, labels); default the "
                 "scene's SEED (or --seed)");
  app.add_option("--lighting", lighting_seed,
                 "with --random: other lighting for the run, drawn from this seed (a test run)");
  app.add_option("--kidnaps", kidnaps,
                 "--variant kidnap: how many; --variant roam: carry the robot this many times to "
                 "another pose on the floor (none unless given)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_option("--waypoints", waypoints, "--variant roam: how many poses")
      ->capture_default_str()
      ->check(CLI::Range(2, 1000));
  app.add_option("--roam-seed", roam_seed, "--variant roam: which roam of the floor")
      ->capture_default_str();
  app.add_option("--minutes", minutes, "--variant long: how long the run lasts at least")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  app.add_option("--out", out_dir,
                 "dataset folder to write (created; existing files are overwritten)");
  app.add_option("--seed", seed, "random seed: pixel noise, wheel slip, route wander, label noise")
      ->capture_default_str();
  app.add_flag("--list", list, "list the built-in scenarios and exit");
  app.add_flag("--quiet", quiet, "no progress output");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  if (list) {
    for (const auto& [name, text] : builtin_scenarios())
      std::printf("%-17s %s\n", name.c_str(), text.c_str());
    return 0;
  }
  if (out_dir.empty()) {
    std::fprintf(stderr, "harmoloc-sim: --out DIR is required (see --help)\n");
    return 2;
  }
  if (!random_seed && (!variant.empty() || run_seed || lighting_seed)) {
    std::fprintf(stderr,
                 "harmoloc-sim: --variant, --run-seed and --lighting go with --random SEED\n");
    return 2;
  }
  try {
    Scenario scenario;
    if (random_seed) {
      scenario = random_scenario(*random_seed);
      if (lighting_seed) scenario = with_other_lighting(scenario, *lighting_seed);
      if (variant == "kidnap") scenario = kidnap_variant(scenario, kidnaps);
      if (variant == "dynamic") scenario = dynamic_variant(scenario);
      if (variant == "long") scenario = long_variant(scenario, minutes);
      if (variant == "coverage") scenario = coverage_variant(scenario);
      if (variant == "roam")
        scenario =
            roam_variant(scenario, roam_seed, waypoints, app.count("--kidnaps") > 0 ? kidnaps : 0);
      if (run_seed)
        seed = *run_seed;
      else if (app.count("--seed") == 0)
        seed = *random_seed;
    } else {
      scenario = load_scenario(scenario_name);
    }
    if (!quiet) {
      std::fprintf(stderr,
                   "harmoloc-sim: scenario '%s' (%ux%u, %.0f Hz, %zu boards, %s), seed %llu -> "
                   "%s\n",
                   scenario.name.c_str(), scenario.camera.width_px, scenario.camera.height_px,
                   scenario.camera.rate_hz, scenario.boards.size(),
                   describe_events(scenario).c_str(), static_cast<unsigned long long>(seed),
                   out_dir.c_str());
    }
    const auto progress = [quiet](std::size_t done, std::size_t total) {
      if (!quiet) std::fprintf(stderr, "\r  rendering frame %zu/%zu", done, total);
      if (!quiet && done == total) std::fprintf(stderr, "\n");
    };
    const SimulationSummary s = simulate_dataset(scenario, seed, out_dir, progress);
    if (random_seed) {
      const std::string config = (std::filesystem::path(out_dir) / "harmoloc.toml").string();
      std::ofstream(config) << firmware_config_toml(scenario);
      if (!quiet) std::fprintf(stderr, "  %s\n", scenario.description.c_str());
    }
    std::printf(
        "wrote %s: %zu frames, %zu encoder frames, %zu labels; route %.2f m, %.1f s, heading "
        "within +-%.0f deg; %s\n",
        out_dir.c_str(), s.frames, s.encoder_frames, s.labels, s.route.length_m, s.route.duration_s,
        s.route.max_heading_offset_deg, describe_events(scenario).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harmoloc-sim: %s\n", e.what());
    return 2;
  }
  return 0;
}
