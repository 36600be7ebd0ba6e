// harmoloc-colours: proposes the boards' colour windows ([[board]] of harmoloc.toml) from a
// recording, and shows and checks what they catch (docs/colours.md).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/colour_preview.hpp"
#include "harmoloc/sim_host/colour_windows.hpp"

namespace {

namespace colours = harmoloc::sim_host::colours;

std::string read_text(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(path + ": no such file");
  std::ifstream f(path);
  std::ostringstream text;
  text << f.rdbuf();
  return text.str();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace harmoloc;
  CLI::App app{
      "harmoloc-colours: choose the colour windows of your own boards from a recording\n"
      "(harmoloc --record DIR, or harmoloc-sim --out DIR) and see what they catch "
      "(docs/colours.md).\n"
      "automatic (default): finds the saturated colours that form compact blobs whose area\n"
      "  changes along the run (--boards N: the N most distinct) and proposes a window each;\n"
      "guided: --frame K --rect NAME:x,y,w,h per board: the window of the colour inside each\n"
      "  rectangle of frame K, kept clear of the colours outside;\n"
      "check: --check CONFIG: the windows of an existing config.\n"
      "Always: every board's area along the run as the firmware counts it, a warning line for a\n"
      "window that catches background, has a constant area or overlaps another, and a preview\n"
      "(PNG masks and an HTML page) in --preview DIR. Writes the [[board]] tables as TOML to\n"
      "--out (with --config BASE: BASE with its boards replaced), else to stdout.\n"
      "Example: harmoloc-colours --dataset run --config harmoloc.toml --out new.toml",
      "harmoloc-colours"};
  std::string dataset_dir, out_path, base_path, check_path, preview_dir;
  int boards = 0, frame = -1;
  std::vector<std::string> rect_texts;
  colours::AutoOptions opt;
  std::size_t area_step = 0;
  int saturation_floor = opt.saturation_floor;
  bool quiet = false;
  app.add_option("--dataset", dataset_dir, "the recording: a dataset folder (frames.csv, frames/)")
      ->required();
  app.add_option("--boards", boards, "automatic: propose this many boards (default: all found)")
      ->check(CLI::Range(1, static_cast<int>(algorithms::kMaxBoards)));
  app.add_option("--frame", frame, "guided: the frame (0-based, as listed in frames.csv)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--rect", rect_texts,
                 "guided: NAME:x,y,w,h, a rectangle around board NAME in --frame (pixels, x and y\n"
                 "of its top-left corner); one per board, in the config's board order");
  app.add_option("--check", check_path, "check the [[board]] windows of this config instead");
  app.add_option("--config", base_path,
                 "a firmware config to start from: --out gets all of it with its boards replaced");
  app.add_option("--out", out_path, "the TOML to write (default: stdout)");
  app.add_option("--preview", preview_dir,
                 "folder for the preview (index.html, PNG masks); default: colours-preview\n"
                 "beside --out, or in the current folder");
  app.add_option("--sample-frames", opt.sample_frames,
                 "automatic: frames looked at, evenly spread over the run")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{2}, std::size_t{100000}));
  app.add_option("--saturation-floor", saturation_floor,
                 "8-bit saturation below which a pixel is never taken for a board's")
      ->capture_default_str()
      ->check(CLI::Range(1, 254));
  app.add_option("--area-step", area_step,
                 "measure the areas on every Nth frame (default: about 1500 frames over the run)");
  app.add_flag("--quiet", quiet, "no progress, no summary (warnings still on stderr)");
  if (const auto status = cli::parse(app, argc, argv)) return *status;

  try {
    const bool guided = !rect_texts.empty() || frame >= 0;
    if (guided && (rect_texts.empty() || frame < 0))
      throw std::runtime_error("guided mode needs --frame K and at least one --rect");
    if (guided && boards > 0)
      throw std::runtime_error("--boards is for automatic mode, not with --rect");
    if (!check_path.empty() && (guided || boards > 0))
      throw std::runtime_error("--check takes the config's windows; no --boards or --rect with it");
    if (rect_texts.size() > algorithms::kMaxBoards)
      throw std::runtime_error("at most " + std::to_string(algorithms::kMaxBoards) + " boards");
    opt.boards = boards;
    opt.saturation_floor = static_cast<std::uint8_t>(saturation_floor);
    const std::string base_text = base_path.empty() ? "" : read_text(base_path);
    if (!base_path.empty()) firmware::load_config(base_path);  // says what is wrong with it

    colours::DatasetFrames frames(dataset_dir);
    // Twenty steps a pass at most: a log of the run stays readable.
    const bool tty = isatty(fileno(stderr)) != 0;
    const auto progress = [quiet, tty](std::size_t done, std::size_t total, const char* what) {
      if (quiet || total == 0) return;
      if (done != total && done * 20 / total == (done == 0 ? 1 : (done - 1) * 20 / total)) return;
      if (tty || done == total)
        std::fprintf(stderr, "%s  %-6s %zu/%zu%s", tty ? "\r" : "", what, done, total,
                     done == total ? "\n" : "");
    };
    opt.progress = progress;

    std::vector<colours::ProposedBoard> proposed;
    std::vector<colours::HueCluster> clusters;
    if (!check_path.empty()) {
      const firmware::FirmwareConfig config = firmware::load_config(check_path);
      for (std::size_t b = 0; b < config.thresholds.count; ++b) {
        colours::ProposedBoard p;
        p.name = config.board_names.names[b];
        p.window = config.thresholds.boards[b];
        const colours::HueRange r = colours::hue_steps_of(p.window);
        p.hue_centre_h8 = (r.lo_h8 + r.width_h8() / 2) % colours::kHueSteps;
        proposed.push_back(p);
      }
    } else if (guided) {
      std::vector<colours::GuidedRect> rects;
      for (const auto& t : rect_texts) {
        try {
          rects.push_back(colours::parse_rect(t));
        } catch (const std::invalid_argument& e) {
          throw std::runtime_error(std::string("--rect: ") + e.what());
        }
      }
      if (static_cast<std::size_t>(frame) >= frames.size())
        throw std::runtime_error("--frame " + std::to_string(frame) + ": the recording has " +
                                 std::to_string(frames.size()) + " frames (0.." +
                                 std::to_string(frames.size() - 1) + ")");
      colours::RgbImage img;
      frames.read(static_cast<std::size_t>(frame), img);
      proposed = colours::propose_guided(img, rects, opt);
    } else {
      const colours::AutoResult r = colours::propose_automatic(frames, opt);
      proposed = r.boards;
      clusters = r.clusters;
      if (proposed.empty())
        throw std::runtime_error(
            "no saturated colour forms blobs whose area changes along the run: no board found "
            "(try --saturation-floor lower, or the guided mode)");
      if (boards > 0 && proposed.size() < static_cast<std::size_t>(boards))
        std::fprintf(stderr, "harmoloc-colours: warning: only %zu colours in the run, not %d\n",
                     proposed.size(), boards);
    }

    const algorithms::ThresholdSet windows = colours::threshold_set_of(proposed);
    const std::size_t step =
        area_step > 0 ? area_step : std::max<std::size_t>(1, (frames.size() + 1499) / 1500);
    const colours::RunAreas areas = colours::measure_run(frames, windows, step, progress);
    std::vector<std::string> names;
    for (const auto& p : proposed) names.push_back(p.name);
    const std::vector<std::string> warnings = colours::window_warnings(areas, names);

    if (check_path.empty()) {
      const std::string toml = colours::boards_toml(proposed, base_text);
      if (out_path.empty()) {
        std::fputs(toml.c_str(), stdout);
      } else {
        std::ofstream f(out_path);
        f << toml;
        if (!f) throw std::runtime_error(out_path + ": cannot write");
      }
    }
    if (preview_dir.empty()) {
      preview_dir =
          out_path.empty()
              ? "colours-preview"
              : (std::filesystem::path(out_path).parent_path() / "colours-preview").string();
    }
    colours::PreviewInput preview{dataset_dir, proposed, areas, warnings, clusters};
    const std::string page = colours::write_preview(preview_dir, frames, preview);

    // The summary goes to stderr when the TOML is on stdout, so that stdout stays TOML.
    FILE* info = out_path.empty() && check_path.empty() ? stderr : stdout;
    if (!quiet) {
      for (const auto& c : clusters) {
        std::fprintf(info, "colour  hue %3d..%3d deg (peak %3d): %s\n", 2 * c.range.lo_h8,
                     2 * c.range.hi_h8, 2 * c.peak_h8, c.verdict.c_str());
      }
      for (std::size_t b = 0; b < proposed.size(); ++b) {
        const auto& w = proposed[b].window;
        std::vector<std::uint32_t> a = areas.area_px[b];
        std::sort(a.begin(), a.end());
        std::fprintf(info,
                     "board   %-10s hue_deg = [%.0f, %.0f], saturation_min = %d, value_min = %d"
                     " (median area %u px, largest %u px)\n",
                     proposed[b].name.c_str(), static_cast<double>(w.hue_min_deg),
                     static_cast<double>(w.hue_max_deg), int{w.saturation_min}, int{w.value_min},
                     a.empty() ? 0U : a[a.size() / 2], a.empty() ? 0U : a.back());
      }
      std::fprintf(info, "preview %s\n", page.c_str());
      if (!out_path.empty()) std::fprintf(info, "wrote   %s\n", out_path.c_str());
    }
    for (const auto& w : warnings)
      std::fprintf(stderr, "harmoloc-colours: warning: %s\n", w.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harmoloc-colours: %s\n", e.what());
    return 2;
  }
  return 0;
}
