// harmoloc-accuracy: the harmonic localizer's accuracy report (docs/training.md). Simulates a
// training and a test run of each route, trains a map on the training run, and scores the
// localizer alone on the test run, next to Wu & Qin's figures; also the known-place test on
// off-route frames, lighting changes, and the error against the number of labelled and
// unlabelled samples.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>

#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/line_chart.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/simulate.hpp"
#include "harmoloc/sim_host/trainer.hpp"

namespace fs = std::filesystem;
using namespace harmoloc;

namespace {

constexpr double kOffRouteM = 0.25;  // farther than this from the training run: off the route

struct Run {
  sim_host::AreaSeries areas;
  std::vector<dataset::StampedPose> truth;  // one per frame
  std::vector<dataset::StampedPose> labels;
};

// Simulates (once; later calls reuse the folder) and segments a run.
Run load_run(const sim_host::Scenario& scenario, std::uint64_t seed, const fs::path& dir,
             const algorithms::ThresholdSet& thresholds, bool quiet) {
  if (!fs::exists(dir / "complete")) {
    if (!quiet)
      std::fprintf(stderr, "  simulating %s (seed %llu)\n", dir.filename().c_str(),
                   static_cast<unsigned long long>(seed));
    fs::remove_all(dir);
    sim_host::simulate_dataset(scenario, seed, dir.string(), nullptr);
    std::ofstream(dir / "complete") << "simulated\n";
  }
  Run run;
  run.areas = sim_host::segment_dataset(dir.string(), thresholds);
  const auto truth = dataset::read_tum((dir / "groundtruth.tum").string());
  // Ground truth has one pose per frame, at the frame's timestamp.
  std::size_t t = 0;
  for (std::uint64_t ns : run.areas.timestamp_ns) {
    const double s = static_cast<double>(ns / 1000U) * 1e-6;
    while (t + 1 < truth.size() && std::fabs(truth[t + 1].t_s - s) < std::fabs(truth[t].t_s - s))
      ++t;
    run.truth.push_back(truth[t]);
  }
  run.labels = dataset::read_tum((dir / "labels.tum").string());
  return run;
}

struct Score {
  double mse_x_cm2 = 0, mse_y_cm2 = 0;
  double flagged_pct = 0;    // frames the known-place test flags
  std::size_t frames = 0;    // with a fix
  std::size_t no_board = 0;  // none of the localizer's boards in view: no fix
};

std::vector<algorithms::HarmonicFix> localise(const algorithms::MapFile& map, const Run& run) {
  std::vector<algorithms::HarmonicFix> fixes;
  for (const auto& a : run.areas.areas) {
    std::array<float, algorithms::HarmonicModel::kMaxFeatures> f{};
    algorithms::areas_to_features(map.model, a, f);
    algorithms::ColumnFeatures c{};
    const bool columns = algorithms::areas_to_columns(map.model, a, c);
    algorithms::FeatureMask use{};
    fixes.push_back(algorithms::harmonic_fix(map.model, a, f, columns ? &c : nullptr, use));
  }
  return fixes;
}

Score score(const algorithms::MapFile& map, const Run& run) {
  const auto fixes = localise(map, run);
  Score s;
  std::size_t flagged = 0;
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    if (!fixes[i].board_seen) {
      ++s.no_board;
      continue;
    }
    ++s.frames;
    const double dx = fixes[i].x_m - run.truth[i].pose.x_m;
    const double dy = fixes[i].y_m - run.truth[i].pose.y_m;
    s.mse_x_cm2 += dx * dx * 1e4;
    s.mse_y_cm2 += dy * dy * 1e4;
    flagged += fixes[i].known_place ? 0 : 1;
  }
  if (s.frames == 0) {
    // No frame showed a board: there is no error to report, and 0 would read as a perfect one.
    s.mse_x_cm2 = s.mse_y_cm2 = s.flagged_pct = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  s.mse_x_cm2 /= static_cast<double>(s.frames);
  s.mse_y_cm2 /= static_cast<double>(s.frames);
  s.flagged_pct = 100.0 * static_cast<double>(flagged) / static_cast<double>(s.frames);
  return s;
}

// A JSON number, or null for a figure without frames to measure it on.
std::string json(double v) {
  if (!std::isfinite(v)) return "null";
  std::ostringstream o;
  o << v;
  return o.str();
}

struct Trained {
  std::unique_ptr<algorithms::MapFile> map = std::make_unique<algorithms::MapFile>();
  sim_host::TrainReport report;
};

Trained train(const Run& run, sim_host::TrainOptions opt) {
  Trained t;
  t.report = sim_host::train_on_areas(run.areas, run.labels, opt, *t.map);
  return t;
}

// A figure without frames to measure it on (NaN) reads "none".
std::string fmt(const char* f, double v) {
  if (!std::isfinite(v)) return "none";
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "harmoloc-accuracy: the harmonic localizer's accuracy report (docs/training.md).\n"
      "For each route: simulates a training run and a separate test run (cached in --work),\n"
      "trains a map on the training run (64 labelled + 140 unlabelled frames, as Wu & Qin 2010) "
      "and\n"
      "scores the localizer alone on every test frame: MSE per axis next to Wu & Qin's figures,\n"
      "the known-place test on on-route and off-route frames, +-30% lighting, and the error "
      "against\n"
      "the number of labelled and unlabelled samples. Writes accuracy.md, accuracy.json and SVG\n"
      "plots to --out.",
      "harmoloc-accuracy"};
  std::string routes_text = "desk-shuttle,desk-left,desk-right,desk-slalom",
              work = "out/accuracy/runs", out = "out/accuracy";
  std::uint64_t train_seed = 1, test_seed = 2;
  bool no_curves = false, no_lighting = false, no_paper = false, quiet = false;
  double max_mse = 0.0;
  app.add_option("--routes", routes_text, "comma-separated scenarios (built-in names or files)")
      ->capture_default_str();
  app.add_option("--work", work, "where simulated runs are kept (reused when present)")
      ->capture_default_str();
  app.add_option("--out", out, "where the report goes")->capture_default_str();
  app.add_option("--train-seed", train_seed, "seed of the training runs")->capture_default_str();
  app.add_option("--test-seed", test_seed, "seed of the test runs")->capture_default_str();
  app.add_flag("--no-curves", no_curves, "skip the labelled/unlabelled sample curves");
  app.add_flag("--no-lighting", no_lighting, "skip the +-30% lighting runs");
  app.add_flag("--no-paper", no_paper, "skip training with Wu & Qin's formulation for comparison");
  app.add_option("--fail-above", max_mse,
                 "exit 1 if any route's MSE on either axis exceeds this (cm^2); 0: never");
  app.add_flag("--quiet", quiet, "only the tables");
  bool all_boards = false;
  int gap = 0;
  double min_improvement = 0.25;
  app.add_flag("--all-boards", all_boards, "train without board selection");
  double margin = 1.5;
  app.add_option("--known-place-margin", margin,
                 "trainer: dissimilarity bound as a multiple of the training samples' p99")
      ->capture_default_str();
  app.add_option("--cv-gap", gap, "trainer: samples left out beside each held-out label")
      ->capture_default_str();
  app.add_option("--min-improvement", min_improvement,
                 "trainer: drop a board only if CV improves by more than this fraction")
      ->capture_default_str();
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  try {
    std::vector<std::string> routes;
    {
      std::stringstream ss(routes_text);
      std::string item;
      while (std::getline(ss, item, ',')) {
        if (!item.empty()) routes.push_back(item);
      }
    }
    if (routes.empty()) throw std::runtime_error("--routes: no route given");
    fs::create_directories(work);
    fs::create_directories(out);
    const firmware::FirmwareConfig config = firmware::default_config();
    sim_host::TrainOptions opt;
    opt.thresholds = config.thresholds;
    opt.max_labelled = 64;
    opt.unlabelled = 140;
    opt.select_boards = !all_boards;
    opt.cv_gap = gap;
    opt.known_place_margin = margin;
    opt.min_improvement = min_improvement;

    struct RouteData {
      std::string name;
      Run train, test, dark, bright;
      Trained ours, paper;
      Score nominal, paper_score, dark_score, bright_score;
      double off_flagged_pct = 0;
      std::size_t off_frames = 0;
    };
    std::vector<RouteData> data(routes.size());
    for (std::size_t r = 0; r < routes.size(); ++r) {
      RouteData& d = data[r];
      sim_host::Scenario s = sim_host::load_scenario(routes[r]);
      d.name = s.name;
      if (!quiet) std::fprintf(stderr, "route %s\n", s.name.c_str());
      sim_host::Scenario train_s = s;
      train_s.labelled_frames = 128;  // the curves use up to 128; the table takes 64 of them
      d.train = load_run(train_s, train_seed, fs::path(work) / (s.name + "-train"), opt.thresholds,
                         quiet);
      d.test = load_run(s, test_seed, fs::path(work) / (s.name + "-test"), opt.thresholds, quiet);
      if (!no_lighting) {
        sim_host::Scenario dark = s, bright = s;
        dark.camera.light_gain = 0.7;
        bright.camera.light_gain = 1.3;
        d.dark = load_run(dark, test_seed, fs::path(work) / (s.name + "-test-light0.7"),
                          opt.thresholds, quiet);
        d.bright = load_run(bright, test_seed, fs::path(work) / (s.name + "-test-light1.3"),
                            opt.thresholds, quiet);
      }
      d.ours = train(d.train, opt);
      d.nominal = score(*d.ours.map, d.test);
      if (!no_lighting) {
        d.dark_score = score(*d.ours.map, d.dark);
        d.bright_score = score(*d.ours.map, d.bright);
      }
      if (!no_paper) {
        sim_host::TrainOptions p = opt;
        p.method = sim_host::TrainMethod::kPaper;
        d.paper = train(d.train, p);
        d.paper_score = score(*d.paper.map, d.test);
      }
    }

    // Known place: each route's map against the other routes' test frames that lie off its
    // training route.
    for (std::size_t r = 0; r < data.size(); ++r) {
      std::size_t off = 0, flagged = 0;
      for (std::size_t o = 0; o < data.size(); ++o) {
        if (o == r) continue;
        const auto fixes = localise(*data[r].ours.map, data[o].test);
        for (std::size_t i = 0; i < fixes.size(); ++i) {
          const auto& p = data[o].test.truth[i].pose;
          double nearest = 1e9;
          for (const auto& q : data[r].train.truth)
            nearest = std::min(nearest, std::hypot(p.x_m - q.pose.x_m, p.y_m - q.pose.y_m));
          if (nearest <= kOffRouteM) continue;
          ++off;
          flagged += fixes[i].known_place ? 0 : 1;
        }
      }
      data[r].off_frames = off;
      data[r].off_flagged_pct =
          off > 0 ? 100.0 * static_cast<double>(flagged) / static_cast<double>(off)
                  : std::numeric_limits<double>::quiet_NaN();
    }

    std::ostringstream md;
    md << "| route | test frames | MSE x (cm^2) | MSE y (cm^2) | Wu & Qin 2010 method, MSE x / y | "
          "features chosen | training (ms) |\n|---|---|---|---|---|---|---|\n";
    for (const auto& d : data) {
      std::string boards;
      for (int b : d.ours.report.boards)
        boards +=
            (boards.empty() ? "" : " ") + config.board_names.names[static_cast<std::size_t>(b)];
      md << "| " << d.name << " | " << d.nominal.frames << " | " << fmt("%.2f", d.nominal.mse_x_cm2)
         << " | " << fmt("%.2f", d.nominal.mse_y_cm2) << " | "
         << (no_paper ? std::string("-")
                      : fmt("%.1f", d.paper_score.mse_x_cm2) + " / " +
                            fmt("%.1f", d.paper_score.mse_y_cm2))
         << " | " << boards << " | " << fmt("%.1f", d.ours.report.train_ms) << " |\n";
    }
    md << "| Wu & Qin 2010 (paper, 4 paths, 500 test frames each) | 2000 | <= 25 | < 20 | | boards "
          "1, "
          "2, "
          "5 by hand | 280 |\n";
    md << "\nKnown-place test (frames flagged as off the trained route):\n\n| map of route | "
          "own test run flagged | off-route frames (> "
       << kOffRouteM * 100 << " cm away, other routes) | of those flagged |\n|---|---|---|---|\n";
    for (const auto& d : data) {
      md << "| " << d.name << " | " << fmt("%.2f %%", d.nominal.flagged_pct) << " | "
         << d.off_frames << " | " << fmt("%.2f %%", d.off_flagged_pct) << " |\n";
    }
    if (!no_lighting) {
      md << "\nLighting (test run with the global brightness scaled):\n\n| route | MSE x / y "
            "nominal | x 0.7 | x 1.3 | worst ratio to nominal | flagged at 0.7 / 1.3 "
            "|\n|---|---|---|---|---|---|\n";
      for (const auto& d : data) {
        // A ratio without frames (NaN) makes the worst one none, not the largest of the rest.
        double worst = 0.0;
        for (const double r : {d.dark_score.mse_x_cm2 / d.nominal.mse_x_cm2,
                               d.dark_score.mse_y_cm2 / d.nominal.mse_y_cm2,
                               d.bright_score.mse_x_cm2 / d.nominal.mse_x_cm2,
                               d.bright_score.mse_y_cm2 / d.nominal.mse_y_cm2})
          if (!(r <= worst)) worst = r;
        md << "| " << d.name << " | " << fmt("%.2f", d.nominal.mse_x_cm2) << " / "
           << fmt("%.2f", d.nominal.mse_y_cm2) << " | " << fmt("%.2f", d.dark_score.mse_x_cm2)
           << " / " << fmt("%.2f", d.dark_score.mse_y_cm2) << " | "
           << fmt("%.2f", d.bright_score.mse_x_cm2) << " / "
           << fmt("%.2f", d.bright_score.mse_y_cm2) << " | " << fmt("%.2f", worst) << " | "
           << fmt("%.1f %%", d.dark_score.flagged_pct) << " / "
           << fmt("%.1f %%", d.bright_score.flagged_pct) << " |\n";
      }
    }

    // Curves: mean MSE over the routes against the number of labelled samples (140 unlabelled)
    // and of unlabelled samples (64 labelled).
    std::vector<double> labelled_x{8, 16, 24, 32, 48, 64, 96, 128},
        unlabelled_x{0, 35, 70, 140, 280, 560};
    sim_host::Series lx{"x axis", "#1f77b4", {}}, ly{"y axis", "#d62728", {}};
    sim_host::Series ux{"x axis", "#1f77b4", {}}, uy{"y axis", "#d62728", {}};
    if (!no_curves) {
      if (!quiet)
        std::fprintf(stderr, "curves: %zu + %zu trainings per route\n", labelled_x.size(),
                     unlabelled_x.size());
      const auto mean_mse = [&](int labelled, int unlabelled, sim_host::Series& sx,
                                sim_host::Series& sy) {
        double mx = 0, my = 0;
        for (const auto& d : data) {
          sim_host::TrainOptions o = opt;
          o.max_labelled = labelled;
          o.unlabelled = unlabelled;
          const Trained t = train(d.train, o);
          const Score s = score(*t.map, d.test);
          mx += s.mse_x_cm2;
          my += s.mse_y_cm2;
        }
        sx.y.push_back(mx / static_cast<double>(data.size()));
        sy.y.push_back(my / static_cast<double>(data.size()));
      };
      for (double l : labelled_x) mean_mse(static_cast<int>(l), 140, lx, ly);
      for (double u : unlabelled_x) mean_mse(64, static_cast<int>(u), ux, uy);
      std::ofstream(fs::path(out) / "labelled.svg") << sim_host::line_chart(
          "Localizer error vs labelled samples (140 unlabelled)", "labelled samples",
          "MSE, cm^2 (mean of routes)", labelled_x, {lx, ly}, 10.0, "target 10 cm^2");
      std::ofstream(fs::path(out) / "unlabelled.svg") << sim_host::line_chart(
          "Localizer error vs unlabelled samples (64 labelled)", "unlabelled samples",
          "MSE, cm^2 (mean of routes)", unlabelled_x, {ux, uy}, 10.0, "target 10 cm^2");
      md << "\nMean MSE over the routes against the number of labelled samples (140 "
            "unlabelled):\n\n"
            "| labelled |";
      for (double v : labelled_x) md << " " << v << " |";
      md << "\n|---|";
      for (std::size_t i = 0; i < labelled_x.size(); ++i) md << "---|";
      md << "\n| MSE x |";
      for (double v : lx.y) md << " " << fmt("%.2f", v) << " |";
      md << "\n| MSE y |";
      for (double v : ly.y) md << " " << fmt("%.2f", v) << " |";
      md << "\n\nAgainst the number of unlabelled samples (64 labelled):\n\n| unlabelled |";
      for (double v : unlabelled_x) md << " " << v << " |";
      md << "\n|---|";
      for (std::size_t i = 0; i < unlabelled_x.size(); ++i) md << "---|";
      md << "\n| MSE x |";
      for (double v : ux.y) md << " " << fmt("%.2f", v) << " |";
      md << "\n| MSE y |";
      for (double v : uy.y) md << " " << fmt("%.2f", v) << " |";
      md << "\n";
    }
    std::ofstream(fs::path(out) / "accuracy.md") << md.str();
    {
      std::ofstream j(fs::path(out) / "accuracy.json");
      j << "{\n  \"routes\": [\n";
      for (std::size_t r = 0; r < data.size(); ++r) {
        const auto& d = data[r];
        j << "    {\"name\": \"" << d.name << "\", \"test_frames\": " << d.nominal.frames
          << ", \"no_board_frames\": " << d.nominal.no_board
          << ", \"mse_x_cm2\": " << json(d.nominal.mse_x_cm2)
          << ", \"mse_y_cm2\": " << json(d.nominal.mse_y_cm2)
          << ", \"own_flagged_pct\": " << json(d.nominal.flagged_pct)
          << ", \"off_route_frames\": " << d.off_frames
          << ", \"off_route_flagged_pct\": " << json(d.off_flagged_pct)
          << ", \"train_ms\": " << d.ours.report.train_ms;
        if (!no_paper) {
          j << ", \"paper_mse_x_cm2\": " << json(d.paper_score.mse_x_cm2)
            << ", \"paper_mse_y_cm2\": " << json(d.paper_score.mse_y_cm2);
        }
        if (!no_lighting) {
          j << ", \"light0.7_mse_x_cm2\": " << json(d.dark_score.mse_x_cm2)
            << ", \"light0.7_mse_y_cm2\": " << json(d.dark_score.mse_y_cm2)
            << ", \"light1.3_mse_x_cm2\": " << json(d.bright_score.mse_x_cm2)
            << ", \"light1.3_mse_y_cm2\": " << json(d.bright_score.mse_y_cm2);
        }
        j << "}" << (r + 1 < data.size() ? "," : "") << "\n";
      }
      j << "  ]\n}\n";
    }
    std::printf("%s\nreport: %s/accuracy.md%s\n", md.str().c_str(), out.c_str(),
                no_curves ? "" : ", labelled.svg, unlabelled.svg");
    if (max_mse > 0.0) {
      for (const auto& d : data) {
        if (d.nominal.frames == 0) {
          std::fprintf(stderr, "harmoloc-accuracy: %s: no test frame shows a board of its map\n",
                       d.name.c_str());
          return 1;
        }
        if (d.nominal.mse_x_cm2 > max_mse || d.nominal.mse_y_cm2 > max_mse) {
          std::fprintf(stderr, "harmoloc-accuracy: %s: MSE %.2f / %.2f cm^2 above %.2f\n",
                       d.name.c_str(), d.nominal.mse_x_cm2, d.nominal.mse_y_cm2, max_mse);
          return 1;
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harmoloc-accuracy: %s\n", e.what());
    return 2;
  }
  return 0;
}
