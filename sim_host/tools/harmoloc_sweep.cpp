// harmoloc-sweep: trains and evaluates the estimator on many random scenes (docs/sweep.md) and
// reports every figure as a distribution over scenes: median, 90th percentile and worst, with
// the worst scenes named by seed, beside the project's own default scene.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/svg.hpp"
#include "harmoloc/sim_host/svg_plot.hpp"
#include "harmoloc/sim_host/svg_ticks.hpp"
#include "sweep_eval.hpp"

namespace fs = std::filesystem;
using namespace harmoloc;
using sim_host::SceneResult;
namespace svg = sim_host::svg;

namespace {

// One figure of the summary: how to read it off a scene, its unit, its targets.
struct Figure {
  std::string key, title, unit;
  std::function<double(const SceneResult&)> value;   // < 0: not measured
  double target_median = -1.0, target_worst = -1.0;  // <= these; -1: none
  bool higher_is_better = false;
};

double cm2(double m2) {
  return m2 < 0.0 ? -1.0 : m2 * 1e4;
}
double cm(double m) {
  return m < 0.0 ? -1.0 : m * 100.0;
}

std::vector<Figure> figures() {
  return {
      {"fix_mse_x", "harmonic localizer alone, MSE x", "cm^2",
       [](const SceneResult& r) { return cm2(r.fix_mse_x_m2); }, 10.0, 25.0},
      {"fix_mse_y", "harmonic localizer alone, MSE y", "cm^2",
       [](const SceneResult& r) { return cm2(r.fix_mse_y_m2); }, 10.0, 25.0},
      {"fix_known", "fixes flagged a known place", "%",
       [](const SceneResult& r) {
         return r.fix_known_fraction < 0.0 ? -1.0 : 100.0 * r.fix_known_fraction;
       },
       -1.0, -1.0, true},
      {"fused_rmse", "fused position RMSE (after first fix + 2 s)", "cm",
       [](const SceneResult& r) { return cm(r.fused_rmse_m); }, 2.0, 4.0},
      {"fused_heading", "fused heading RMSE", "deg",
       [](const SceneResult& r) { return r.fused_heading_rmse_deg; }},
      {"startup", "start-up: from the first fix until under 5 cm (held 1 s)", "s",
       [](const SceneResult& r) { return r.startup_s; }, -1.0, 2.0},
      {"converge", "time from the first fix until under 5 cm for good", "s",
       [](const SceneResult& r) { return r.converge_s; }},
      {"fused_max", "fused max error after first fix + 2 s", "cm",
       [](const SceneResult& r) { return cm(r.fused_max_m); }, -1.0, 10.0},
      {"kidnap_recovered", "kidnaps back under 10 cm within 1 s", "%",
       [](const SceneResult& r) {
         return r.kidnaps == 0 ? -1.0
                               : 100.0 * static_cast<double>(r.kidnaps_recovered_1s) /
                                     static_cast<double>(r.kidnaps);
       },
       -1.0, -1.0, true},
      {"false_alarms", "false kidnap alarms per 10 minutes", "",
       [](const SceneResult& r) {
         return r.long_minutes <= 0.0
                    ? -1.0
                    : static_cast<double>(r.long_false_alarms) * 10.0 / r.long_minutes;
       },
       -1.0, 0.0},
      {"dynamic_max", "dynamic run (person, moved board): max error", "cm",
       [](const SceneResult& r) { return cm(r.dynamic_max_m); }, -1.0, 10.0},
      {"long_max", "long nominal run: max error", "cm",
       [](const SceneResult& r) { return cm(r.long_max_m); }, -1.0, 10.0},
      {"placement", "training frames placed by odometry, RMSE", "mm",
       [](const SceneResult& r) {
         return r.placement_rmse_m < 0.0 ? -1.0 : 1000.0 * r.placement_rmse_m;
       }},
      {"train_ms", "training time (area log in memory)", "ms",
       [](const SceneResult& r) { return r.train_ms; }},
  };
}

// What the scenes add up to.
struct Totals {
  std::size_t kidnaps = 0, recovered = 0, alarms = 0, failed = 0;
  double minutes = 0.0;
};

Totals totals_of(const std::vector<SceneResult>& results) {
  Totals t;
  for (const SceneResult& r : results) {
    t.kidnaps += r.kidnaps;
    t.recovered += r.kidnaps_recovered_1s;
    t.alarms += r.long_false_alarms;
    t.minutes += r.long_minutes;
    t.failed += r.error.empty() ? 0 : 1;
  }
  return t;
}

struct Distribution {
  std::size_t n = 0;
  double median = 0, p90 = 0, worst = 0;
  std::vector<std::uint64_t> worst_seeds;  // up to 3, worst first
};

Distribution distribution(const std::vector<SceneResult>& results, const Figure& f) {
  std::vector<std::pair<double, std::uint64_t>> v;
  for (const SceneResult& r : results) {
    if (!r.error.empty()) continue;
    const double x = f.value(r);
    if (x >= 0.0 && std::isfinite(x)) v.emplace_back(x, r.seed);
  }
  Distribution d;
  d.n = v.size();
  if (v.empty()) return d;
  // "Worse" is larger, or smaller for higher-is-better figures.
  std::sort(v.begin(), v.end(), [&](const auto& a, const auto& b) {
    return f.higher_is_better ? a.first > b.first : a.first < b.first;
  });
  const auto at = [&](double q) {
    const double pos = q * static_cast<double>(v.size() - 1);
    const auto lo = static_cast<std::size_t>(std::floor(pos));
    const auto hi = std::min(v.size() - 1, lo + 1);
    return v[lo].first + (pos - static_cast<double>(lo)) * (v[hi].first - v[lo].first);
  };
  d.median = at(0.5);
  d.p90 = at(0.9);
  d.worst = v.back().first;
  for (std::size_t i = 0; i < 3 && i < v.size(); ++i)
    d.worst_seeds.push_back(v[v.size() - 1 - i].second);
  return d;
}

nlohmann::json to_json(const SceneResult& r) {
  nlohmann::json j;
  j["seed"] = r.seed;
  j["scene"] = r.summary;
  if (!r.error.empty()) j["error"] = r.error;
  j["train_ms"] = r.train_ms;
  j["train_frames"] = r.train_frames;
  j["placement_rmse_m"] = r.placement_rmse_m;
  j["placement_heading_rmse_deg"] = r.placement_heading_rmse_deg;
  j["cv_rmse_x_m"] = r.cv_rmse_x_m;
  j["cv_rmse_y_m"] = r.cv_rmse_y_m;
  j["boards_used"] = r.boards_used;
  j["fix_mse_x_m2"] = r.fix_mse_x_m2;
  j["fix_mse_y_m2"] = r.fix_mse_y_m2;
  j["fix_known_fraction"] = r.fix_known_fraction;
  j["fix_known_mse_x_m2"] = r.fix_known_mse_x_m2;
  j["fix_known_mse_y_m2"] = r.fix_known_mse_y_m2;
  j["first_fix_s"] = r.first_fix_s;
  j["startup_s"] = r.startup_s;
  j["converge_s"] = r.converge_s;
  j["fused_rmse_m"] = r.fused_rmse_m;
  j["fused_heading_rmse_deg"] = r.fused_heading_rmse_deg;
  j["fused_max_m"] = r.fused_max_m;
  j["kidnaps"] = r.kidnaps;
  j["kidnaps_detected"] = r.kidnaps_detected;
  j["kidnaps_recovered_1s"] = r.kidnaps_recovered_1s;
  j["kidnap_mean_recovery_s"] = r.kidnap_mean_recovery_s;
  j["kidnap_misses_t_s"] = r.kidnap_misses_t_s;
  j["dynamic_max_m"] = r.dynamic_max_m;
  j["dynamic_rmse_m"] = r.dynamic_rmse_m;
  j["long_minutes"] = r.long_minutes;
  j["long_false_alarms"] = r.long_false_alarms;
  j["long_max_m"] = r.long_max_m;
  j["long_rmse_m"] = r.long_rmse_m;
  j["seconds"] = r.seconds;
  return j;
}

std::string fmt(double v, int decimals = 2) {
  if (v < 0.0 || !std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

// A strip plot: one dot per scene on a horizontal axis, the median marked, the targets dashed,
// the worst scene labelled by seed; the default scene as a ring. Hover a dot for its seed.
std::string strip_svg(const Figure& f, const std::vector<SceneResult>& results,
                      const SceneResult* reference) {
  const Distribution d = distribution(results, f);
  std::vector<std::pair<double, std::uint64_t>> v;
  for (const SceneResult& r : results) {
    const double x = r.error.empty() ? f.value(r) : -1.0;
    if (x >= 0.0 && std::isfinite(x)) v.emplace_back(x, r.seed);
  }
  const double ref = reference != nullptr ? f.value(*reference) : -1.0;
  double hi = 0.0;
  for (const auto& p : v) hi = std::max(hi, p.first);
  hi = std::max({hi, f.target_worst, f.target_median, ref});
  if (f.unit == "%") hi = 100.0;
  if (!(hi > 0.0) || !std::isfinite(hi)) hi = 1.0;
  // The axis from 0 to a whole number of round steps.
  const double step = svg::nice_step(hi, 4);
  hi = std::ceil(hi / step - 1e-9) * step;
  const double width = 640.0;
  const svg::Area area{20.0, 22.0, width - 40.0, 38.0};
  const svg::Scale sx{0.0, hi, area.left, area.right()};
  constexpr const char* kDot = "#0066cc";
  constexpr const char* kWorst = "#cc0000";
  svg::Canvas c(width, 92.0);
  c.text(area.left, 14.0, f.title + (f.unit.empty() ? "" : " (" + f.unit + ")"), "start", 11.0,
         svg::kTextColour, " font-weight=\"bold\"");
  c.line(area.left, area.bottom(), area.right(), area.bottom(), "#888888", 1.0);
  for (const svg::Tick& t : svg::make_ticks(sx, step)) {
    c.line(t.px, area.bottom(), t.px, area.bottom() + 4.0, "#888888", 1.0);
    c.text(t.px, area.bottom() + 16.0, t.label, "middle", 11.0, svg::kMutedColour);
  }
  const auto vline = [&](double x, const char* colour, const char* label, bool dashed) {
    c.line(sx(x), area.top, sx(x), area.bottom(), colour, 1.0,
           dashed ? " stroke-dasharray=\"4,3\"" : "");
    // The label right of the line, or left of it where it would run off the plot.
    const bool fits = sx(x) + 3.0 + svg::text_width(label, 11.0) <= width;
    c.text(fits ? sx(x) + 3.0 : sx(x) - 3.0, area.top + 8.0, label, fits ? "start" : "end", 11.0,
           colour);
  };
  if (f.target_worst >= 0.0) vline(f.target_worst, kWorst, "target (worst)", true);
  if (f.target_median > 0.0) vline(f.target_median, "#ee8800", "target (median)", true);
  if (d.n > 0) vline(d.median, kDot, "median", false);
  const auto with_tooltip = [&c](const std::string& tip, const auto& draw) {
    c.raw("<g><title>" + svg::escape(tip) + "</title>\n");
    draw();
    c.raw("</g>\n");
  };
  std::size_t i = 0;
  for (const auto& [x, seed] : v) {
    const double jitter = static_cast<double>((i++ * 7) % 11) - 5.0;
    with_tooltip("seed " + std::to_string(seed) + ": " + fmt(x), [&] {
      c.circle(sx(x), area.bottom() - 12.0 + jitter, 3.0, kDot, " fill-opacity=\"0.6\"");
    });
  }
  if (d.n > 0 && !d.worst_seeds.empty()) {
    c.text(std::min(sx(d.worst), width - 60.0), area.bottom() - 22.0,
           "seed " + std::to_string(d.worst_seeds.front()), "start", 11.0, kWorst);
  }
  if (ref >= 0.0) {
    with_tooltip("default scene: " + fmt(ref), [&] {
      c.circle(sx(ref), area.bottom() - 12.0, 5.0, "none",
               " stroke=\"#008800\" stroke-width=\"2\"");
    });
  }
  return svg::inline_svg(c.finish());
}

void write_html(const std::string& path, const std::vector<SceneResult>& results,
                const SceneResult* reference, const std::string& command) {
  std::ofstream o(path);
  o << "<!doctype html><html><head><meta charset='utf-8'><title>harmoloc sweep</title>"
    << "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto}"
    << "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:3px 6px;"
    << "text-align:right}th{background:#eee}td.l{text-align:left}.bad{color:#c00;"
    << "font-weight:bold}</style></head><body>";
  o << "<h1>harmoloc sweep over random scenes</h1><p>" << svg::escape(command) << "</p>";
  std::size_t failed = 0;
  for (const SceneResult& r : results) failed += r.error.empty() ? 0 : 1;
  o << "<p>" << results.size() << " scenes, " << failed
    << " failed. Each dot is a scene; the green ring is the project's own default scene "
       "(desk-shuttle). Hover a dot for its seed.</p>";
  o << "<table><tr><th class='l'>figure</th><th>scenes</th><th>median</th><th>90th pct</th>"
    << "<th>worst</th><th class='l'>worst seeds</th><th>default scene</th><th>target</th></tr>";
  for (const Figure& f : figures()) {
    const Distribution d = distribution(results, f);
    std::string seeds;
    for (std::uint64_t s : d.worst_seeds) seeds += (seeds.empty() ? "" : ", ") + std::to_string(s);
    std::string target;
    if (f.target_median >= 0.0) target += "median &le; " + fmt(f.target_median, 1);
    if (f.target_worst >= 0.0)
      target += std::string(target.empty() ? "" : ", ") + "worst &le; " + fmt(f.target_worst, 1);
    const bool bad = (f.target_worst >= 0.0 && d.n > 0 && d.worst > f.target_worst) ||
                     (f.target_median >= 0.0 && d.n > 0 && d.median > f.target_median);
    o << "<tr><td class='l'>" << svg::escape(f.title + (f.unit.empty() ? "" : " (" + f.unit + ")"))
      << "</td><td>" << d.n << "</td><td>" << fmt(d.median) << "</td><td>" << fmt(d.p90)
      << "</td><td" << (bad ? " class='bad'" : "") << ">" << fmt(d.worst) << "</td><td class='l'>"
      << seeds << "</td><td>" << (reference != nullptr ? fmt(f.value(*reference)) : "-")
      << "</td><td class='l'>" << target << "</td></tr>";
  }
  o << "</table>";
  for (const Figure& f : figures()) o << "<div>" << strip_svg(f, results, reference) << "</div>";
  o << "<h2>Scenes</h2><table><tr><th>seed</th><th class='l'>scene</th><th>fix MSE x/y (cm^2)</th>"
    << "<th>fused RMSE (cm)</th><th>start-up (s)</th><th>kidnaps in 1 s</th>"
    << "<th>false alarms</th><th>dynamic max (cm)</th><th class='l'>error</th></tr>";
  for (const SceneResult& r : results) {
    o << "<tr><td>" << r.seed << "</td><td class='l'>" << svg::escape(r.summary) << "</td><td>"
      << fmt(cm2(r.fix_mse_x_m2), 1) << " / " << fmt(cm2(r.fix_mse_y_m2), 1) << "</td><td>"
      << fmt(cm(r.fused_rmse_m)) << "</td><td>" << fmt(r.startup_s) << "</td><td>"
      << r.kidnaps_recovered_1s << "/" << r.kidnaps << "</td><td>" << r.long_false_alarms
      << "</td><td>" << fmt(cm(r.dynamic_max_m), 1) << "</td><td class='l'>" << svg::escape(r.error)
      << "</td></tr>";
  }
  o << "</table></body></html>\n";
}

}  // namespace

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
  app.add_option("--first", first, "first scene seed")->capture_default_str();
  app.add_option("--scenes", scenes, "number of scenes (seeds first .. first + N - 1)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  std::vector<std::uint64_t> seed_list;
  app.add_option("--seeds", seed_list,
                 "these scene seeds instead of --first/--scenes (e.g. --seeds 5,7,11)")
      ->delimiter(',')
      ->excludes("--first")
      ->excludes("--scenes");
  app.add_option("--jobs", jobs, "scenes evaluated in parallel")->capture_default_str();
  app.add_option("--out", out_dir, "folder for sweep.json and index.html")->capture_default_str();
  app.add_option("--parts", parts, "which runs: nominal,kidnap,dynamic,long")
      ->capture_default_str();
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
  app.add_flag("--quick", quick, "a short sweep: 5 kidnaps, a 1-minute long run");
  app.add_flag("--no-default-scene", no_default, "leave out the project's own default scene");
  app.add_flag("--quiet", quiet, "no progress on stderr");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;
  if (quick) {
    opt.kidnaps = std::min(opt.kidnaps, 5);
    opt.long_minutes = std::min(opt.long_minutes, 1.0);
  }
  opt.nominal = parts.find("nominal") != std::string::npos;
  opt.kidnap = parts.find("kidnap") != std::string::npos;
  opt.dynamic = parts.find("dynamic") != std::string::npos;
  opt.long_run = parts.find("long") != std::string::npos;
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
    j["options"] = {{"kidnaps", opt.kidnaps}, {"long_minutes", opt.long_minutes}, {"parts", parts}};
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
  std::printf("wrote %s/sweep.json and %s/index.html\n", out_dir.c_str(), out_dir.c_str());
  return totals.failed > 0 ? 1 : 0;
}
