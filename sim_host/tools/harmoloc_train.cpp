// harmoloc-train: trains the harmonic map from a recorded (or simulated) run and a few labels.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/coverage_plot.hpp"
#include "harmoloc/sim_host/trainer.hpp"

namespace {

std::string board_list(const std::vector<int>& boards, const harmoloc::firmware::BoardNames& n) {
  std::string out;
  for (int b : boards) out += (out.empty() ? "" : " ") + n.names[static_cast<std::size_t>(b)];
  return out.empty() ? "-" : out;
}

// An image angle under the law as "1.54 deg left of the centre column".
std::string side_of_centre(double angle_rad) {
  char text[64];
  std::snprintf(text, sizeof text, "%.2f deg %s of the centre column",
                std::fabs(angle_rad) * 180.0 / harmoloc::algorithms::kPi,
                angle_rad < 0.0 ? "left" : "right");
  return text;
}

// A floor map's visibility tables: from the fitted geometry, board by board, or the kernel's and
// why.
void print_geometry_tables(const harmoloc::sim_host::GeometryReport& g,
                           const harmoloc::firmware::BoardNames& n) {
  if (!g.tables_asked) return;
  if (g.law_from_camera) {
    constexpr double kDeg = 180.0 / harmoloc::algorithms::kPi;
    std::printf(
        "geometry      column-to-angle law from the fitted camera: half field of view %.2f deg "
        "(a1 %.4f, a3 %.4f); the optical axis %s\n",
        (0.5 * g.law_a1_rad + 0.125 * g.law_a3_rad) * kDeg, g.law_a1_rad, g.law_a3_rad,
        side_of_centre(g.law_axis_rad).c_str());
    if (!g.law_rows.empty())
      std::printf(
          "              fitted at the rows the boards were seen at: %.0f-%.0f%% of the height "
          "(10-90%% of the sightings, 0 the top)\n",
          100.0 * g.law_rows.front(), 100.0 * g.law_rows.back());
  }
  const harmoloc::sim_host::GeometryTablesReport& t = g.tables;
  if (!t.applied) {
    std::printf(
        "geometry      visibility tables: the kernel's (from the frames near each place), %s\n",
        t.skipped.c_str());
    return;
  }
  std::printf(
      "geometry      visibility tables from the geometry (%zu cells, %.0f ms); angle gain %.3f "
      "(the kernel's %.3f):\n",
      t.cells, t.ms, t.geometry_angle_gain, t.kernel_angle_gain);
  for (std::size_t k = 0; k < t.from_geometry.size(); ++k) {
    const char* name = k < n.names.size() ? n.names[k].c_str() : "?";
    if (!(t.geometry_sigma[k] > 0.0)) continue;
    constexpr double kDeg = 180.0 / harmoloc::algorithms::kPi;
    std::printf(
        "              %s %s: area noise %.4f with the geometry, %.4f with the kernel; "
        "bearing spread %.2f deg with the geometry, %.2f with the kernel%s\n",
        name, t.from_geometry[k] ? "from the geometry" : "kernel kept", t.geometry_sigma[k],
        t.kernel_sigma[k], t.geometry_bearing_sigma_rad[k] * kDeg,
        t.kernel_bearing_sigma_rad[k] * kDeg,
        t.from_geometry[k] && t.kernel_bearings[k] ? " (the kernel's bearings kept)" : "");
  }
  if (g.projected_boards == 0) return;
  std::printf(
      "geometry      bearings of the %zu boards from the geometry projected from the fitted "
      "camera at each pose (map version 16); their spread against the run's frames:",
      g.projected_boards);
  constexpr double kDeg = 180.0 / harmoloc::algorithms::kPi;
  for (std::size_t k = 0; k < g.projected_spread_rad.size(); ++k) {
    if (!(g.projected_spread_rad[k] > 0.0)) continue;
    std::printf(" %s %.2f", k < n.names.size() ? n.names[k].c_str() : "?",
                g.projected_spread_rad[k] * kDeg);
  }
  std::printf(" deg\n");
  if (g.projected_area_sigma.empty()) return;
  std::printf(
      "geometry      areas of %zu boards projected as well (map version 17); the projection's "
      "area noise against the run's frames, and whether it took the board's areas:",
      g.projected_area_boards);
  for (std::size_t k = 0; k < g.projected_area_sigma.size(); ++k) {
    if (!(g.projected_area_sigma[k] > 0.0)) continue;
    std::printf(" %s %.4g (%s)", k < n.names.size() ? n.names[k].c_str() : "?",
                g.projected_area_sigma[k], g.projected_area_taken[k] ? "taken" : "tables kept");
  }
  std::printf("\n");
}

// The --fit-geometry section: the fitted camera, then each board.
void print_geometry(const harmoloc::sim_host::GeometryReport& g,
                    const harmoloc::firmware::BoardNames& n) {
  if (!g.tried) {
    std::printf("geometry      not fitted: %s\n",
                g.skipped.empty() ? "the frames were not placed by odometry" : g.skipped.c_str());
    return;
  }
  const harmoloc::sim_host::SceneGeometryFit& f = g.fit;
  const harmoloc::sim_host::CameraSpec& c = f.camera;
  if (!f.ok) {
    std::printf("geometry      not fitted: fewer than two boards fit (%.0f ms)\n", g.ms);
  } else {
    std::printf(
        "geometry      camera: field of view %.1f deg (pinhole; started at %.1f), "
        "k1 %.3f, k2 %.3f, "
        "pitch %.1f deg, principal point %+.1f, %+.1f px, %.3f m ahead of the axle, %.3f m up "
        "(given); residual column %.2f px, row %.2f px RMS (%.0f ms)\n",
        c.horizontal_fov_deg, g.camera_start.horizontal_fov_deg, c.k1, c.k2, c.pitch_deg,
        c.principal_offset_x_px, c.principal_offset_y_px, c.forward_offset_m, c.height_m,
        f.rms_column_px, f.rms_row_px, g.ms);
  }
  if (g.frame_scales) {
    std::printf(
        "              residual scales taken to the %ux%u frame (with a 320x240 frame's, fewer "
        "than two boards fitted)\n",
        g.camera_start.width_px, g.camera_start.height_px);
  }
  if (g.heading_rounds > 0) {
    std::printf(
        "              headings refined by the boards: %d rounds, the frames turned by %.2f deg "
        "RMS (the fit above is from them)\n",
        g.heading_rounds, g.heading_offset_rms_rad * 180.0 / harmoloc::algorithms::kPi);
  }
  // Each board, fitted or not: a failed fit says which boards failed and by how much.
  for (std::size_t k = 0; k < f.boards.size(); ++k) {
    const harmoloc::sim_host::BoardFit& b = f.boards[k];
    const char* name = k < n.names.size() ? n.names[k].c_str() : "?";
    if (!b.ok) {
      if (b.sightings_used == 0) {
        std::printf("              %s not fitted (not placed from its bearings, or never seen)\n",
                    name);
      } else {
        std::printf(
            "              %s not fitted (%zu sightings, %.0f%% beyond the robust threshold; "
            "residual column %.2f px, row %.2f px)\n",
            name, b.sightings_used, 100.0 * b.outlier_share, b.rms_column_px, b.rms_row_px);
      }
      continue;
    }
    std::printf(
        "              %s at (%.2f, %.2f, %.2f) m, %.2f x %.2f m, facing %.0f deg, "
        "%zu sightings, residual column %.2f px, row %.2f px\n",
        name, b.board.centre_x_m, b.board.centre_y_m, b.board.centre_z_m, b.board.width_m,
        b.board.height_m, b.board.facing_yaw_rad * 180.0 / harmoloc::algorithms::kPi,
        b.sightings_used, b.rms_column_px, b.rms_row_px);
  }
  if (f.ok) print_geometry_tables(g, n);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace harmoloc;
  CLI::App app{
      "harmoloc-train: train the harmonic localizer's map on the host (docs/training.md).\n"
      "Input is a run the robot recorded: a dataset folder (frames) or an area log\n"
      "(harmoloc --record DIR writes both), plus labelled poses (TUM) at some times of the run.\n"
      "With the run's wheel odometry every frame is placed between the labels, which may fall at\n"
      "any time; without it a label names the frame nearest its time (--label-tolerance-ms).\n"
      "A label's heading is used only where the labels carry one (a non-zero yaw); the result\n"
      "says which. The trainer chooses the feature boards, the neighbour graph, gamma and the\n"
      "kernel width per axis by k-fold cross-validation over the labelled frames, and calibrates\n"
      "the known-place test. The map records the colour thresholds and frame size it was trained\n"
      "with; the firmware refuses a map that does not match its config.",
      "harmoloc-train"};
  std::string dataset, areas, labels, out, config_path, boards_text, method = "neighbour";
  int unlabelled = -1, folds = 5, max_labelled = -1;
  double ratio = 2.2;
  bool quiet = false, all_boards = false;
  auto* input = app.add_option_group("input", "the recorded run (one of)");
  input->add_option("--dataset", dataset, "dataset folder of the training run (frames)");
  input->add_option("--areas", areas, "area log of the training run (harmoloc --record-areas)");
  input->require_option(1);
  app.add_option("--labels", labels,
                 "labelled poses (TUM) on the run's clock (or shifted onto it by --label-offset);\n"
                 "with wheel odometry any times within the run, without it frame timestamps")
      ->required();
  std::string label_offset = "0";
  app.add_option(
         "--label-offset", label_offset,
         "SECONDS added to every label's time (the reference's clock against the robot's),\n"
         "or 'auto': estimated from the run's wheel odometry (docs/training.md)")
      ->capture_default_str();
  double label_tolerance_ms = 0.5;
  app.add_option("--label-tolerance-ms", label_tolerance_ms,
                 "without wheel odometry: a label names the frame nearest its time within this")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  std::string encoders;
  app.add_option("--encoders", encoders,
                 "with --areas: the run's encoder log (candump -l log or GPIO recording), decoded\n"
                 "with the config's [can] layout and [odometry] geometry; a dataset folder brings "
                 "its own");
  std::string placed_path;
  app.add_option("--placed", placed_path,
                 "write where the odometry placed every frame (TUM), to check the placement");
  bool no_odometry = false;
  app.add_flag("--no-odometry", no_odometry,
               "do not place the frames by the wheel odometry between the labels: Wu & Qin's\n"
               "labelled + unlabelled samples only (the forward map then interpolates labels)");
  bool no_bearings = false;
  app.add_flag("--no-bearings", no_bearings,
               "do not store the boards' bearings (where each board is seen across the frame) in\n"
               "the map: the filter then weighs by areas alone, as maps before version 6");
  bool no_columns = false;
  app.add_flag("--no-columns", no_columns,
               "do not try the boards' centroid columns in the harmonic localizer's kernel (map\n"
               "format 12): areas only, as maps before it; for a co-processor build, which has\n"
               "no room for them");
  bool column_gain = false;
  app.add_flag("--column-gain", column_gain,
               "measure how a board's area changes with its column in the frame (lens,\n"
               "vignetting) on the run's passes and take it out of the harmonic localizer's\n"
               "areas (map format 13). Experimental: on random scenes more kidnaps recovered,\n"
               "but on a strong barrel lens the fix got worse near the frame's sides\n"
               "(docs/training.md)");
  bool heading_terms = false;
  CLI::Option* terms_flag = app.add_flag(
      "--heading-terms", heading_terms,
      "model the boards' areas over the heading too where the run drove a place at\n"
      "several headings (a floor; map format 7), kept where they predict other passes\n"
      "better, fitted over the lanes nearby too (kernels up to 35 cm; a floor trains\n"
      "about 4 times longer). Experimental: not for the bare-metal kernels (no room);\n"
      "on random floors they bettered the heading and kidnaps, the position only in\n"
      "the median (docs/sweep.md)");
  bool visibility = false, no_visibility = false;
  CLI::Option* visibility_flag =
      app.add_flag("--visibility", visibility,
                   "model each board's area by whether the lens sees it at the heading, on a\n"
                   "route map too: per place its area seen whole from the camera's place, its\n"
                   "bearing and width (map format 10; needs bearings and the camera's offset;\n"
                   "not with --heading-terms, not for the bare-metal kernels). docs/filter.md.\n"
                   "A floor map has it by default")
          ->excludes(terms_flag);
  app.add_flag("--no-visibility", no_visibility,
               "a floor map without visibility: the boards' areas averaged over the headings\n"
               "driven at each place (as before map format 10; what the bare-metal kernels\n"
               "can hold)")
      ->excludes(visibility_flag);
  double camera_forward = std::numeric_limits<double>::quiet_NaN();
  app.add_option(
         "--camera-forward-m", camera_forward,
         "the camera's offset ahead of the wheel axle's centre (metres; default: the\n"
         "dataset's camera.forward_offset_m). Given, the boards' bearings are mapped from\n"
         "the camera's place and from every heading the run drove (map format 9);\n"
         "0, or no offset known: from the axle's place, each from the run's own heading there")
      ->check(CLI::Range(-1.0, 1.0));
  bool fit_geometry = false;
  app.add_flag("--fit-geometry", fit_geometry,
               "also fit the camera (field of view, lens, pitch, principal point, offset) and\n"
               "each board's centre, size and facing to the run's areas and centroids, and\n"
               "print them, on any map (needs the bearings, an area log or dataset with row\n"
               "sums, and the camera's height; seconds to tens of seconds)");
  bool visibility_from_geometry = false, visibility_from_frames = false;
  CLI::Option* visibility_from_geometry_flag =
      app.add_flag("--visibility-from-geometry", visibility_from_geometry,
                   "a floor map's visibility tables (each place's board area seen whole, bearing\n"
                   "and width) from the camera and boards fitted to the run, board by board where\n"
                   "they predict the run's areas better than the frames near each place\n"
                   "(docs/training.md). The default where the camera's height is known; given, an\n"
                   "unknown height is an error");
  visibility_from_geometry_flag->excludes("--no-visibility");
  app.add_flag("--visibility-from-frames", visibility_from_frames,
               "a floor map's visibility tables from the frames near each place only, as\n"
               "when the camera's height is not known (no geometry fit)")
      ->excludes(visibility_from_geometry_flag);
  bool law_from_frames = false;
  app.add_flag("--law-from-frames", law_from_frames,
               "keep the column-to-angle law triangulated from the frames' centroid columns; by\n"
               "default a map whose visibility tables the geometry fit serves takes the fitted\n"
               "camera's law, and its forward map is trained again with it (docs/training.md)");
  bool refine_headings = false;
  app.add_flag("--refine-headings", refine_headings,
               "where the geometry is fitted: refine the placed frames' headings by the boards it\n"
               "holds (a frame's heading error moves every board's column alike) and train the\n"
               "forward map with them. Experimental (docs/training.md)");
  bool projected_bearings = true;
  app.add_flag("--projected-bearings,!--no-projected-bearings", projected_bearings,
               "store the fitted camera and the outlines of the boards whose visibility tables\n"
               "come from the geometry fit, and have the filter project their bearings at each\n"
               "particle's pose instead of reading the map's cells (map version 15,\n"
               "docs/bearings.md; on by default, --no-projected-bearings turns it and the\n"
               "projected areas off)");
  bool projected_areas = true;
  app.add_flag("--projected-areas,!--no-projected-areas", projected_areas,
               "with the projected bearings: also predict those boards' areas from the\n"
               "projected outline at each particle's pose, where that predicts the run's areas\n"
               "at least as closely as the map's tables (map version 17, docs/filter.md; on by\n"
               "default)");
  double camera_height = 0.0;
  app.add_option("--camera-height-m", camera_height,
                 "the camera's optical centre above the floor (metres), the geometry fit's\n"
                 "scale (default: the dataset's camera.height_m)")
      ->check(CLI::Range(0.01, 5.0));
  app.add_option("--out", out, "map file to write")->required();
  std::string coverage_path;
  app.add_option("--coverage", coverage_path,
                 "also write a picture (SVG) of where and from which headings the map can\n"
                 "localize: the places near the training run, each with the headings it covers");
  app.add_option("--config", config_path,
                 "firmware config whose colour thresholds to use (default: built-in)");
  app.add_option("--unlabelled", unlabelled,
                 "number of unlabelled frames (default: --ratio x labelled)");
  app.add_option("--ratio", ratio, "unlabelled per labelled frame when --unlabelled is not given")
      ->capture_default_str();
  app.add_option("--labelled", max_labelled,
                 "use at most this many of the labels, evenly spread (default: all)");
  app.add_option("--boards", boards_text,
                 "feature boards, 1-based, comma separated (e.g. 1,2,5); default: chosen by CV");
  app.add_flag("--all-boards", all_boards, "use every board that changes; no selection");
  app.add_option(
         "--method", method,
         "neighbour: k-nearest-neighbour graph (default); paper: Wu & Qin's complete graph\n"
         "with the normalised Laplacian, for comparison")
      ->check(CLI::IsMember({"neighbour", "paper"}))
      ->capture_default_str();
  double margin = 1.5;
  app.add_option("--known-place-margin", margin,
                 "known-place bound: this many times the 99th percentile of the training samples'\n"
                 "leave-one-out dissimilarity (raise it if too many on-route frames are flagged)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 20.0));
  app.add_option("--folds", folds, "cross-validation folds")
      ->capture_default_str()
      ->check(CLI::Range(2, 64));
  std::size_t forward_tiles = algorithms::ForwardMap::kMaxTiles;
  app.add_option("--forward-tiles", forward_tiles,
                 "most tiles of 8x8 cells the forward map may store (the cells coarsen to fit);\n"
                 "the firmware holds " +
                     std::to_string(algorithms::ForwardMap::kMaxTiles) +
                     ", the bare-metal kernels 64 (docs/baremetal.md)")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, algorithms::ForwardMap::kMaxTiles));
  app.add_flag("--quiet", quiet, "print only the result line");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  try {
    const firmware::FirmwareConfig config =
        config_path.empty() ? firmware::default_config() : firmware::load_config(config_path);
    sim_host::TrainOptions opt;
    opt.dataset_dir = dataset;
    opt.areas_path = areas;
    opt.labels_path = labels;
    opt.encoders_path = encoders;
    opt.can_layout = config.can_layout;
    opt.geometry = config.geometry;
    opt.use_odometry = !no_odometry;
    opt.bearings = !no_bearings;
    opt.column_features = !no_columns;
    opt.column_gain = column_gain;
    if (heading_terms) opt.forward.heading_ridges = sim_host::kHeadingRidges;
    opt.forward.visibility = visibility;
    opt.forward.visibility_on_floors = !no_visibility;
    opt.forward.camera_forward_m = camera_forward;
    opt.fit_geometry = fit_geometry;
    opt.visibility_from_geometry = !visibility_from_frames;
    opt.geometry_tables_required = visibility_from_geometry;
    opt.law_from_geometry = !law_from_frames;
    opt.refine_headings = refine_headings;
    opt.projected_bearings = projected_bearings;
    opt.projected_areas = projected_bearings && projected_areas;
    opt.camera_height_m = camera_height;
    opt.label_tolerance_ns = static_cast<std::uint64_t>(std::llround(label_tolerance_ms * 1e6));
    if (label_offset == "auto") {
      opt.label_offset_auto = true;
    } else {
      std::size_t used = 0;
      try {
        opt.label_offset_s = std::stod(label_offset, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != label_offset.size() || !std::isfinite(opt.label_offset_s) ||
          std::fabs(opt.label_offset_s) > 1e6) {
        std::fprintf(stderr, "harmoloc-train: --label-offset: '%s' is not seconds or 'auto'\n",
                     label_offset.c_str());
        return 2;
      }
    }
    if (!encoders.empty() && areas.empty())
      throw std::runtime_error("--encoders goes with --areas (a dataset folder has its own log)");
    opt.thresholds = config.thresholds;
    opt.unlabelled = unlabelled;
    opt.unlabelled_ratio = ratio;
    opt.max_labelled = max_labelled;
    opt.folds = folds;
    opt.select_boards = !all_boards;
    opt.known_place_margin = margin;
    opt.forward.max_tiles = forward_tiles;
    opt.method =
        method == "paper" ? sim_host::TrainMethod::kPaper : sim_host::TrainMethod::kNeighbourGraph;
    if (!boards_text.empty()) {
      std::stringstream ss(boards_text);
      std::string item;
      while (std::getline(ss, item, ',')) {
        try {
          opt.boards.push_back(std::stoi(item) - 1);
        } catch (const std::exception&) {
          throw std::runtime_error("--boards: '" + item + "' is not a board number");
        }
      }
    }
    const auto map_storage = std::make_unique<algorithms::MapFile>();  // large: not on the stack
    algorithms::MapFile& map = *map_storage;
    const sim_host::TrainReport r = sim_host::train_map(opt, map);
    const std::vector<std::uint8_t> bytes = algorithms::encode_map(map);
    if (!placed_path.empty()) {
      if (!r.placement.used)
        throw std::runtime_error("--placed: the frames were not placed by odometry");
      std::vector<dataset::StampedPose> poses;
      for (std::size_t i = 0; i < r.placement.poses.size(); ++i) {
        if (r.placement.placed[i])
          poses.push_back(dataset::StampedPose{r.placement.times_s[i], r.placement.poses[i]});
      }
      dataset::write_tum(placed_path, poses);
    }
    std::ofstream f(out, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
    if (!f) throw std::runtime_error(out + ": cannot write");
    if (!coverage_path.empty()) {
      if (!map.forward.present())
        throw std::runtime_error("--coverage: the map has no forward map to picture");
      // Known places: within two kernel widths of the run (where the forward map's values are
      // the run's own, not its nearest frames' carried out).
      const double known_m =
          std::max(2.0 * r.forward.bandwidth_m, static_cast<double>(map.forward.cell_m));
      std::ofstream svg(coverage_path);
      svg << sim_host::coverage_svg(map.forward, known_m,
                                    "Coverage of " + out + ": places and headings");
      if (!svg) throw std::runtime_error(coverage_path + ": cannot write");
    }
    if (!quiet) {
      const auto& names = config.board_names;
      if (r.label_offset_estimated) {
        std::printf(
            "labels        time offset %+.3f s +- %.3f s, estimated from the wheel odometry "
            "(label distances fit to %.1f mm RMS, %.1f mm without the offset)\n",
            r.label_offset_s, r.label_offset.standard_error_s,
            1000.0 * r.label_offset.rms_at_best_m, 1000.0 * r.label_offset.rms_at_zero_m);
      } else if (r.label_offset_s != 0.0) {
        std::printf("labels        time offset %+.3f s (--label-offset)\n", r.label_offset_s);
      }
      std::printf("labels        heading %s\n",
                  r.labels_have_yaw
                      ? "used: the labels carry one (the placement follows it)"
                      : "not used: the labels carry none (the placement works it out from the "
                        "positions and the odometry)");
      const sim_host::PlacementReport& pl = r.placement;
      if (pl.used) {
        std::printf(
            "frames        %zu (%zu without any board in view, %zu too far outside the "
            "labelled stretch)\n",
            r.frames, r.empty_frames, pl.beyond_labels);
        std::printf(
            "placement     %zu frames placed by wheel odometry between %zu labels over %.2f m "
            "(a label every %.0f cm);\n"
            "              labels predicted from their neighbours' odometry: median %.1f mm, "
            "worst %.1f mm (label %d)\n",
            pl.frames, r.labelled, pl.travel_m, 100.0 * pl.label_spacing_m,
            1000.0 * pl.median_label_residual_m, 1000.0 * pl.worst_label_residual_m,
            pl.worst_label + 1);
        if (pl.odometry.used) {
          const auto& c = pl.odometry;
          std::printf(
              "odometry      calibrated on %d stretches of the run: left wheel x %.4f, right x "
              "%.4f, track x %.4f;\n"
              "              labels fit their stretch to %.1f mm (%.1f mm as configured)\n",
              c.stretches, c.scale.left, c.scale.right, c.scale.track, 1000.0 * c.misfit_after_m,
              1000.0 * c.misfit_before_m);
        } else {
          std::printf("odometry      not calibrated (too few labels over the run)\n");
        }
        std::printf("samples       %zu placed frames (every frame a sample, evenly spread)\n",
                    r.unlabelled);
      } else {
        std::printf(
            "frames        %zu (%zu without any board in view); labels matched %zu, unmatched "
            "%zu\n",
            r.frames, r.empty_frames, r.labelled, r.labels_unmatched);
        std::printf("samples       %zu labelled + %zu unlabelled (ratio 1:%.1f)\n", r.labelled,
                    r.unlabelled,
                    static_cast<double>(r.unlabelled) / static_cast<double>(r.labelled));
      }
      if (!r.constant_boards.empty()) {
        std::printf("boards        left out, area never changes: %s\n",
                    board_list(r.constant_boards, names).c_str());
      }
      for (const auto& step : r.board_steps) {
        if (step.dropped < 0) {
          std::printf("boards        start with %s: CV RMSE x %.2f cm, y %.2f cm\n",
                      board_list(step.boards, names).c_str(), 100.0 * step.cv_rmse_x_m,
                      100.0 * step.cv_rmse_y_m);
        } else {
          std::printf("boards        drop %s (CV improves enough): x %.2f cm, y %.2f cm\n",
                      names.names[static_cast<std::size_t>(step.dropped)].c_str(),
                      100.0 * step.cv_rmse_x_m, 100.0 * step.cv_rmse_y_m);
        }
      }
      if (pl.used) {
        std::printf("kernel        %s\n",
                    r.noise_weighted ? "each board in units of its noise (CV prefers it)"
                                     : "board areas as they are (CV prefers it to noise units)");
        if (r.column_weight > 0.0)
          std::printf(
              "columns       the boards' centroid columns weigh in, weight %.2f (CV: x %.2f cm, "
              "y %.2f cm with areas only)\n",
              r.column_weight, 100.0 * r.areas_only_cv_rmse_x_m, 100.0 * r.areas_only_cv_rmse_y_m);
        else if (r.areas_only_cv_rmse_x_m > 0.0)
          std::printf("columns       areas only (the centroid columns do not improve CV enough)\n");
        const sim_host::ColumnGainReport& g = r.column_gain;
        if (opt.column_gain && g.fitted)
          std::printf(
              "column gain   a board's area x %.2f a quarter frame from the centre, x %.2f at the "
              "side (%zu boards in %zu pairs of frames over one place)\n",
              g.gain.at(0.25), g.gain.at(0.5), g.observations, g.pairs);
        else if (opt.column_gain)
          std::printf(
              "column gain   none (%zu boards seen twice from one place: too few, or no fit)\n",
              g.observations);
        if (r.local_linear_ridge > 0.0)
          std::printf(
              "fix           local linear, ridge %.2f (CV: x %.2f cm, y %.2f cm with the "
              "plain kernel average)\n",
              r.local_linear_ridge, 100.0 * r.kernel_average_cv_rmse_x_m,
              100.0 * r.kernel_average_cv_rmse_y_m);
        else
          std::printf(
              "fix           kernel average (a local linear correction does not improve "
              "CV enough)\n");
      }
      // The selection never goes below kFixCheckMinBoards (KernelSelectionOptions::min_boards).
      constexpr std::size_t kFloor = algorithms::kFixCheckMinBoards;
      const bool chosen =
          opt.boards.empty() && !all_boards && opt.method != sim_host::TrainMethod::kPaper;
      std::printf("features      %s%s\n", board_list(r.boards, names).c_str(),
                  !chosen                    ? ""
                  : r.boards.size() < kFloor ? " (every board whose area changes)"
                  : r.boards.size() == kFloor
                      ? " (three are kept at least: a fix from fewer cannot "
                        "be checked for a moved board)"
                  : r.board_steps.size() > 1 ? ""
                                             : " (no board's removal improves CV enough)");
      const auto axis = [&](const char* name, const sim_host::AxisReport& a) {
        if (pl.used) {
          std::printf(
              "%s axis        query sigma %.4g  (CV RMSE %.2f cm, frames predicted from other "
              "passes)\n",
              name, a.sigma, 100.0 * a.cv_rmse_m);
        } else if (a.neighbours > 0) {
          std::printf(
              "%s axis        %d-neighbour graph, gamma %.3g, query sigma %.4g  (%d-fold CV "
              "RMSE %.2f cm)\n",
              name, a.neighbours, a.gamma, a.sigma, folds, 100.0 * a.cv_rmse_m);
        } else {
          std::printf(
              "%s axis        complete graph, sigma %.4g, gamma %.3g  (%d-fold CV RMSE "
              "%.2f cm)\n",
              name, a.sigma, a.gamma, folds, 100.0 * a.cv_rmse_m);
        }
      };
      axis("x", r.x);
      axis("y", r.y);
      std::printf(
          "known place   Bray-Curtis dissimilarity to the nearest sample <= %.3g, distance <= %.3g "
          "(%% of frame)\n",
          r.dissimilarity_bound, r.known_place_bound);
      if (r.local_fix_error_max_m > 0.0) {
        std::printf(
            "fix error     near each sample, from the cross-validated fixes that named its place: "
            "median %.2f cm, largest %.2f cm\n",
            100.0 * r.local_fix_error_median_m, 100.0 * r.local_fix_error_max_m);
      }
      if (r.has_forward_map) {
        const auto& fw = r.forward;
        std::string sig;
        for (std::size_t b = 0; b < fw.sigma.size(); ++b) {
          char item[64];
          std::snprintf(item, sizeof item, "%s%s %.3g", sig.empty() ? "" : ", ",
                        names.names[b].c_str(), fw.sigma[b]);
          sig += fw.sigma[b] > 0.0 ? item : "";
        }
        const algorithms::ForwardMap& grid = map.forward;
        std::printf(
            "forward map   cells of %.1f cm over %ux%u, %u tiles of %ux%u stored near the run "
            "(%zu cells, of at most %zu tiles)\n",
            100.0 * static_cast<double>(grid.cell_m), grid.columns, grid.rows, grid.tile_count,
            algorithms::ForwardMap::kTileSide, algorithms::ForwardMap::kTileSide,
            grid.stored_cells(), algorithms::ForwardMap::kMaxTiles);
        if (fw.by_odometry > 0) {
          std::printf(
              "              from %zu frames placed by odometry, kernel %.1f cm, heading from the "
              "placement\n",
              fw.by_odometry, 100.0 * fw.bandwidth_m);
        } else {
          std::printf(
              "              from %zu frames (%zu placed by labels, %zu by the map), kernel %.1f "
              "cm, heading %s\n",
              fw.interpolated + fw.from_harmonic, fw.interpolated, fw.from_harmonic,
              100.0 * fw.bandwidth_m,
              fw.has_heading ? "from the labels" : "unknown (labels have none)");
        }
        std::printf("board noise   %s (%% of frame, against other passes)\n", sig.c_str());
        if (fw.has_heading) {
          const double turn_deg = fw.pass_heading_spread_rad * 180.0 / algorithms::kPi;
          std::printf(
              "passes        %.1f cm from the nearest other pass (median), %.1f deg turned from it "
              "(upper quartile): %s\n",
              100.0 * fw.pass_spread_m, turn_deg,
              algorithms::is_floor_map(map.calibration)
                  ? "a floor map (lanes at several headings; the filter drops the route terms)"
                  : "a route map");
          std::printf(
              "headings      %.0f%% of the circle covered near the run (mean over its cells: a "
              "place is known from the headings within about 45 deg of those it was driven at)\n",
              100.0 * fw.covered_heading_fraction);
          if (map.forward.has_heading_terms) {
            char kernel[96] = "";
            if (fw.heading_bandwidth_m > 0.0)
              std::snprintf(kernel, sizeof kernel, ", fitted over %.0f cm%s",
                            100.0 * fw.heading_bandwidth_m,
                            fw.heading_narrow_level ? " on the narrow kernel's level" : "");
            std::printf(
                "heading terms the boards' areas modelled over the heading too: they predict "
                "other passes to %.3g RMS against %.3g without (ridge %g%s)\n",
                fw.validation_rmse, fw.mean_validation_rmse, fw.heading_ridge, kernel);
          } else if (fw.heading_terms_validation_rmse > 0.0)
            std::printf(
                "heading terms none: over the heading the areas predict other passes to %.3g RMS, "
                "no better than %.3g without\n",
                fw.heading_terms_validation_rmse, fw.validation_rmse);
        }
        if (fw.has_bearings) {
          std::string spread;
          for (std::size_t b = 0; b < fw.bearing_sigma_rad.size(); ++b) {
            if (!(fw.bearing_sigma_rad[b] > 0.0)) continue;
            char item[64];
            std::snprintf(item, sizeof item, "%s%s %.2f", spread.empty() ? "" : ", ",
                          b < names.names.size() ? names.names[b].c_str() : "?",
                          fw.bearing_sigma_rad[b] * 180.0 / algorithms::kPi);
            spread += item;
          }
          char from[64] = "the axle's place";
          if (fw.bearing_camera_forward_m != 0.0)
            std::snprintf(from, sizeof from, "the camera's place, %.0f mm ahead of the axle",
                          1000.0 * fw.bearing_camera_forward_m);
          std::printf(
              "bearing noise %s (deg, against other passes; %zu of %zu cells hold one, seen from "
              "%s)\n",
              spread.c_str(), fw.bearing_cells, grid.stored_cells(), from);
          if (fw.visibility) {
            std::printf(
                "visibility    each board's area seen whole from the camera's place, in view by "
                "its bearing; towards the frame's edge it grows by 1 + %.2f a^2",
                fw.visibility_angle_gain);
            if (grid.visibility_axis_rad != 0.0F)
              std::printf(", a from the optical axis (%s)",
                          side_of_centre(static_cast<double>(grid.visibility_axis_rad)).c_str());
            std::printf("\n");
          } else if (fw.visibility_wanted)
            std::printf(
                "visibility    none: it needs the bearings seen from the camera's place "
                "(--camera-forward-m) and no heading terms\n");
        } else {
          std::printf("bearing noise none in the map (%s)\n",
                      !opt.bearings   ? "--no-bearings"
                      : r.bearings.ok ? "too few residuals against other passes"
                                      : "the lens's law could not be learnt");
        }
      }
      if (r.bearings.ok) {
        std::size_t placed = 0;
        for (const auto& p : r.bearings.placements) placed += p.placed ? 1U : 0U;
        std::printf(
            "bearings      %zu of %zu boards placed from their centroid columns (%zu rays), "
            "half field of view %.1f deg, residual %.2f deg RMS (%.0f ms)\n",
            placed, r.bearings.boards, r.bearings.rays,
            r.bearings.half_fov_rad() * 180.0 / algorithms::kPi,
            r.bearings.rms_residual_rad * 180.0 / algorithms::kPi, r.bearings_ms);
        for (std::size_t k = 0; k < r.bearings.placements.size(); ++k) {
          const auto& p = r.bearings.placements[k];
          if (!p.placed) continue;
          std::printf("              %s at (%.2f, %.2f) m, %zu rays, residual %.2f deg\n",
                      k < names.names.size() ? names.names[k].c_str() : "?", p.x_m, p.y_m, p.frames,
                      p.rms_residual_rad * 180.0 / algorithms::kPi);
        }
      }
      if (opt.fit_geometry)
        print_geometry(r.geometry, names);
      else
        print_geometry_tables(r.geometry, names);
      if (r.segment_ms > 0.0) {
        std::printf("time          segmentation %.0f ms, training %.1f ms, forward map %.0f ms\n",
                    r.segment_ms, r.train_ms, r.forward_ms);
      } else {
        std::printf("time          training %.1f ms, forward map %.0f ms\n", r.train_ms,
                    r.forward_ms);
      }
    }
    std::printf("wrote %s (%zu bytes, %u samples)\n", out.c_str(), bytes.size(),
                map.model.sample_count);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harmoloc-train: %s\n", e.what());
    return 2;
  }
  return 0;
}
