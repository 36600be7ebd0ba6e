// harmoloc-sweep: trains and evaluates the estimator on many random scenes (docs/sweep.md) and
// reports every figure as a distribution over scenes: median, 90th percentile and worst, with
// the worst scenes named by seed, beside the project's own default scene.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "sweep_eval.hpp"
#include "sweep_parts.hpp"

namespace fs = std::filesystem;
using namespace harmoloc;
using sim_host::SceneResult;
using namespace sweep_detail;

int main(int argc, char** argv) {
  CLI::App app{
      "harmoloc-sweep: train and evaluate the estimator on many random scenes and report every\n"
      "figure as a distribution over scenes (median, 90th percentile, worst, the worst scenes\n"
      "named by seed), beside the project's own default scene. Each scene: a training run with\n"
      "64 labels, a test run of the same route (other noise and lighting), a run with kidnaps,\n"
      "a run with a person walking through and a board moved, and a long nominal run for false\n"
      "alarms, all through the firmware's own cycle, rendered in memory (docs/sweep.md).",
      "harmoloc-sweep"};
  std::uint64_t first = 1;
  int scenes = 30;
  unsigned jobs = std::max(1U, std::thread::hardware_concurrency());
  std::string out_dir = "out/sweep";
  bool quick = false, no_default = false, quiet = false;
  std::string parts = "nominal,kidnap,dynamic,long";
  sim_host::SweepOptions opt;
  // Seed 0 is the default scene's in sweep.json and the traces.
  const CLI::Validator scene_seed(
      [](std::string& value) {
        unsigned long long seed = 1;
        try {
          seed = std::stoull(value);
        } catch (const std::exception&) {
          return std::string();  // not a number: the option's own conversion says so
        }
        return seed == 0 ? std::string("random scene seeds are 1 and up (0 is the default scene's)")
                         : std::string();
      },
      "SEED >= 1");
  app.add_option("--first", first, "first scene seed (random scenes are 1 and up)")
      ->capture_default_str()
      ->check(scene_seed);
  app.add_option("--scenes", scenes, "number of scenes (seeds first .. first + N - 1)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  std::vector<std::uint64_t> seed_list;
  app.add_option("--seeds", seed_list,
                 "these scene seeds instead of --first/--scenes (e.g. --seeds 5,7,11)")
      ->delimiter(',')
      ->check(scene_seed)
      ->excludes("--first")
      ->excludes("--scenes");
  app.add_option("--jobs", jobs, "scenes evaluated in parallel")->capture_default_str();
  app.add_option("--out", out_dir, "folder for sweep.json and index.html")->capture_default_str();
  app.add_option("--parts", parts,
                 "which runs: nominal,kidnap,dynamic,long (the trained route's) and floor (a map "
                 "trained on a coverage run of the floor around the route, replayed on --roams "
                 "roams of that floor that no training drove)")
      ->capture_default_str();
  app.add_option("--roams", opt.roams, "floor: roams per scene (8 poses each)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--floor-kidnaps", opt.floor_kidnaps,
                 "floor: kidnaps to anywhere on the floor, in one more roam (0: none)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100));
  app.add_option("--kidnaps", opt.kidnaps, "kidnaps per scene")->capture_default_str();
  app.add_option("--long-minutes", opt.long_minutes, "length of the long nominal run")
      ->capture_default_str();
  std::string config_path;
  app.add_option("--config", config_path,
                 "the firmware's config for every run (as `harmoloc --config`; the colour "
                 "windows come from each scene)");
  app.add_option("--trace", opt.trace_dir,
                 "also write every run frame by frame (truth, estimate, fix, verdicts) as CSV "
                 "into this folder: seed-N-nominal.csv, -kidnap, -dynamic, -long");
  app.add_flag("--heading-terms", opt.heading_terms,
               "floor: train the floor's map with heading terms (harmoloc-train --heading-terms)");
  CLI::Option* visibility_flag =
      app.add_flag("--visibility", opt.visibility,
                   "floor: train the floor's map with visibility (harmoloc-train --visibility; a\n"
                   "floor map has it by default)");
  app.add_flag("--no-visibility", opt.no_visibility,
               "floor: train the floor's map without visibility (harmoloc-train --no-visibility),\n"
               "for comparison")
      ->excludes(visibility_flag);
  bool geometry_flag = false, frames_flag = false;
  CLI::Option* geometry_option =
      app.add_flag("--visibility-from-geometry", geometry_flag,
                   "floor: the floor map's visibility tables from the camera and boards fitted\n"
                   "to the coverage run, the camera's height given as the scene's (the default;\n"
                   "kept for older command lines)")
          ->excludes("--no-visibility");
  app.add_flag("--visibility-from-frames", frames_flag,
               "floor: the floor map's visibility tables from the frames near each place only\n"
               "(harmoloc-train --visibility-from-frames), for comparison")
      ->excludes(geometry_option)
      ->excludes("--no-visibility");
  app.add_option("--geometry-noise-ratio", opt.geometry_noise_ratio,
                 "floor, unless --visibility-from-frames: a board takes the geometry's tables\n"
                 "when its noise with them is at most this times the kernel's (measured near\n"
                 "the lanes, its best case)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  app.add_flag("--law-from-frames", opt.law_from_frames,
               "floor: keep the column-to-angle law triangulated from the frames, not the fitted\n"
               "camera's (harmoloc-train --law-from-frames), for comparison");
  app.add_flag("--refine-headings", opt.refine_headings,
               "floor: refine the coverage run's headings by the boards the geometry fit holds\n"
               "(harmoloc-train --refine-headings). Experimental");
  app.add_flag("--projected-bearings,!--no-projected-bearings", opt.projected_bearings,
               "floor: project the bearings of the geometry's boards from the fitted camera at\n"
               "each particle's pose (harmoloc-train --projected-bearings; on by default,\n"
               "--no-projected-bearings turns it and the projected areas off)");
  app.add_flag("--projected-areas,!--no-projected-areas", opt.projected_areas,
               "floor: project the areas of the geometry's boards as well, where the projection\n"
               "predicts the coverage run's areas at least as closely as the tables\n"
               "(harmoloc-train --projected-areas; on by default)");
  app.add_flag("--axle-bearings", opt.axle_bearings,
               "keep the maps' bearings over the axle's place, as when the camera's offset is\n"
               "not given (harmoloc-train --camera-forward-m 0), for comparison");
  app.add_flag("--column-gain", opt.column_gain,
               "train the maps with the area's gain by column (harmoloc-train --column-gain)");
  app.add_flag("--quick", quick, "a short sweep: 5 kidnaps, a 1-minute long run");
  app.add_flag("--no-default-scene", no_default, "leave out the project's own default scene");
  app.add_flag("--quiet", quiet, "no progress on stderr");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;
  opt.visibility_from_geometry = !frames_flag && !opt.no_visibility;
  if (quick) {
    opt.kidnaps = std::min(opt.kidnaps, 5);
    opt.long_minutes = std::min(opt.long_minutes, 1.0);
  }
  {
    std::stringstream list(parts);
    std::string part;
    while (std::getline(list, part, ',')) {
      if (part != "nominal" && part != "kidnap" && part != "dynamic" && part != "long" &&
          part != "floor") {
        std::fprintf(stderr,
                     "harmoloc-sweep: --parts: unknown part '%s' (nominal, kidnap, dynamic, long, "
                     "floor)\n",
                     part.c_str());
        return 2;
      }
    }
  }
  opt.nominal = parts.find("nominal") != std::string::npos;
  opt.kidnap = parts.find("kidnap") != std::string::npos;
  opt.dynamic = parts.find("dynamic") != std::string::npos;
  opt.long_run = parts.find("long") != std::string::npos;
  opt.floor = parts.find("floor") != std::string::npos;
  jobs = std::max(1U, jobs);
  if (!config_path.empty()) {
    try {
      opt.config = firmware::load_config(config_path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "harmoloc-sweep: %s\n", e.what());
      return 2;
    }
  }
  if (!opt.trace_dir.empty()) {
    std::error_code ec;
    fs::create_directories(opt.trace_dir, ec);
    if (ec || !fs::is_directory(opt.trace_dir)) {
      std::fprintf(stderr, "harmoloc-sweep: --trace %s: cannot create the folder\n",
                   opt.trace_dir.c_str());
      return 2;
    }
  }
  if (seed_list.empty())
    for (int i = 0; i < scenes; ++i) seed_list.push_back(first + static_cast<std::uint64_t>(i));
  scenes = static_cast<int>(seed_list.size());

  std::vector<SceneResult> results(static_cast<std::size_t>(scenes));
  std::vector<char> evaluated(results.size(), 0);
  // sweep.json and index.html, written again after every scene (a long sweep that is stopped
  // keeps what it measured) and at the end. Scenes not yet evaluated are left out.
  SceneResult reference;
  bool have_reference = false;
  std::string command;
  for (int a = 0; a < argc; ++a) command += (a ? " " : "") + std::string(argv[a]);
  const auto write_outputs = [&](const std::vector<SceneResult>& all, bool final_write) {
    std::vector<SceneResult> finished;
    for (std::size_t i = 0; i < all.size(); ++i)
      if (evaluated[i]) finished.push_back(all[i]);
    fs::create_directories(out_dir);
    nlohmann::json j;
    j["seeds"] = seed_list;
    j["scenes"] = scenes;
    j["scenes_done"] = finished.size();
    j["complete"] = final_write;
    j["options"] = {{"kidnaps", opt.kidnaps},
                    {"long_minutes", opt.long_minutes},
                    {"parts", parts},
                    {"heading_terms", opt.heading_terms},
                    {"axle_bearings", opt.axle_bearings},
                    {"column_gain", opt.column_gain},
                    {"visibility", opt.visibility},
                    {"no_visibility", opt.no_visibility},
                    {"visibility_from_geometry", opt.visibility_from_geometry},
                    {"geometry_noise_ratio", opt.geometry_noise_ratio},
                    {"law_from_frames", opt.law_from_frames},
                    {"refine_headings", opt.refine_headings},
                    {"projected_bearings", opt.projected_bearings},
                    {"projected_areas", opt.projected_bearings && opt.projected_areas},
                    {"roams", opt.roams}};
    j["results"] = nlohmann::json::array();
    for (const SceneResult& r : finished) j["results"].push_back(to_json(r));
    if (have_reference) j["default_scene"] = to_json(reference);
    for (const Figure& f : figures()) {
      const Distribution d = distribution(finished, f);
      j["summary"][f.key] = {{"title", f.title},
                             {"unit", f.unit},
                             {"scenes", d.n},
                             {"median", d.median},
                             {"p90", d.p90},
                             {"worst", d.worst},
                             {"worst_seeds", d.worst_seeds}};
      if (have_reference) j["summary"][f.key]["default_scene"] = f.value(reference);
    }
    const Totals t = totals_of(finished);
    j["kidnaps_total"] = t.kidnaps;
    j["kidnaps_recovered_1s_total"] = t.recovered;
    j["false_alarms_total"] = t.alarms;
    j["long_minutes_total"] = t.minutes;
    j["failed_scenes"] = t.failed;
    if (opt.floor) {
      j["floor_kidnaps_total"] = t.floor_kidnaps;
      j["floor_kidnaps_recovered_2s_total"] = t.floor_recovered;
    }
    std::ofstream(fs::path(out_dir) / "sweep.json") << j.dump(1) << "\n";
    write_html((fs::path(out_dir) / "index.html").string(), finished,
               have_reference ? &reference : nullptr, command);
  };

  std::atomic<std::size_t> next{0}, done{0};
  std::mutex io;
  const auto say = [&](const std::string& line) {
    if (quiet) return;
    std::lock_guard<std::mutex> lock(io);
    std::fprintf(stderr, "%s\n", line.c_str());
  };
  const auto worker = [&]() {
    for (;;) {
      const std::size_t i = next++;
      if (i >= results.size()) return;
      const std::uint64_t seed = seed_list[i];
      const SceneResult r =
          sim_host::evaluate_random_scene(seed, opt, [&](const std::string& step) {
            say("harmoloc-sweep: seed " + std::to_string(seed) + ": " + step);
          });
      char line[256];
      std::snprintf(line, sizeof line,
                    "harmoloc-sweep: [%zu/%d] seed %llu done in %.0f s: fix MSE %s/%s cm^2, "
                    "fused %s cm, kidnaps %zu/%zu, false alarms %zu%s%s",
                    ++done, scenes, static_cast<unsigned long long>(seed), r.seconds,
                    fmt(cm2(r.fix_mse_x_m2), 1).c_str(), fmt(cm2(r.fix_mse_y_m2), 1).c_str(),
                    fmt(cm(r.fused_rmse_m)).c_str(), r.kidnaps_recovered_1s, r.kidnaps,
                    r.long_false_alarms, r.error.empty() ? "" : "; FAILED: ", r.error.c_str());
      say(line);
      if (opt.floor) {
        std::snprintf(line, sizeof line,
                      "harmoloc-sweep: seed %llu floor: fused %s cm, heading %s deg, max %s cm, "
                      "fix MSE %s/%s cm^2, kidnaps %zu/%zu%s%s",
                      static_cast<unsigned long long>(seed), fmt(cm(r.floor_rmse_m)).c_str(),
                      fmt(r.floor_heading_rmse_deg).c_str(), fmt(cm(r.floor_max_m)).c_str(),
                      fmt(cm2(r.floor_fix_mse_x_m2), 1).c_str(),
                      fmt(cm2(r.floor_fix_mse_y_m2), 1).c_str(), r.floor_kidnaps_recovered_2s,
                      r.floor_kidnaps,
                      r.floor_error.empty() ? "" : "; FAILED: ", r.floor_error.c_str());
        say(line);
      }
      const std::lock_guard<std::mutex> lock(io);
      results[i] = r;
      evaluated[i] = 1;
      write_outputs(results, false);
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < jobs; ++t) threads.emplace_back(worker);
  if (!no_default) {
    say("harmoloc-sweep: the default scene (desk-shuttle)");
    SceneResult r = sim_host::evaluate_scene(sim_host::load_scenario("desk-shuttle"),
                                             firmware::default_config().thresholds, 0, opt);
    r.summary = "default scene: " + r.summary;
    const std::lock_guard<std::mutex> lock(io);
    reference = r;
    have_reference = true;
  }
  for (std::thread& t : threads) t.join();
  write_outputs(results, true);
  const Totals totals = totals_of(results);

  // The table on stdout.
  std::printf("%-48s %6s %8s %8s %8s  %-14s %8s\n", "figure", "scenes", "median", "p90", "worst",
              "worst seeds", "default");
  for (const Figure& f : figures()) {
    const Distribution d = distribution(results, f);
    std::string seeds;
    for (std::uint64_t s : d.worst_seeds) seeds += (seeds.empty() ? "" : ",") + std::to_string(s);
    const std::string title = f.title + (f.unit.empty() ? "" : " (" + f.unit + ")");
    std::printf("%-48.48s %6zu %8s %8s %8s  %-14s %8s\n", title.c_str(), d.n, fmt(d.median).c_str(),
                fmt(d.p90).c_str(), fmt(d.worst).c_str(), seeds.c_str(),
                have_reference ? fmt(f.value(reference)).c_str() : "-");
  }
  std::printf(
      "kidnaps back under 10 cm within 1 s: %zu of %zu (%.1f%%); false alarms: %zu in %.1f "
      "minutes; failed scenes: %zu\n",
      totals.recovered, totals.kidnaps,
      totals.kidnaps > 0
          ? 100.0 * static_cast<double>(totals.recovered) / static_cast<double>(totals.kidnaps)
          : 0.0,
      totals.alarms, totals.minutes, totals.failed);
  if (opt.floor) {
    std::printf("floor: kidnaps back under 10 cm within 2 s: %zu of %zu (%.1f%%)\n",
                totals.floor_recovered, totals.floor_kidnaps,
                totals.floor_kidnaps > 0 ? 100.0 * static_cast<double>(totals.floor_recovered) /
                                               static_cast<double>(totals.floor_kidnaps)
                                         : 0.0);
  }
  std::printf("wrote %s/sweep.json and %s/index.html\n", out_dir.c_str(), out_dir.c_str());
  return totals.failed > 0 ? 1 : 0;
}
