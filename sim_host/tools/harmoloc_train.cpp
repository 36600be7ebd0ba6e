// harmoloc-train: trains the harmonic map from a recorded (or simulated) run and a few labels.
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>

#include "harmoloc/firmware/config.hpp"
#include "harmoloc/sim_host/trainer.hpp"

int main(int argc, char** argv) {
  using namespace harmoloc;
  CLI::App app{
      "harmoloc-train: train the harmonic localizer's map (seed 000, eq. 7-8) on the host.\n"
      "Frames whose timestamp has a label in --labels are labelled; an evenly spread subset of the "
      "other\n"
      "frames is used unlabelled. Kernel width (sigma) and regularisation (gamma) are chosen per "
      "axis by\n"
      "k-fold cross-validation over the labelled frames. The map records the colour thresholds and "
      "the\n"
      "frame size it was trained with; the firmware refuses a map that does not match its config.",
      "harmoloc-train"};
  std::string dataset, labels, out, config_path, boards_text;
  int unlabelled = -1, folds = 5;
  double ratio = 2.2;
  bool quiet = false;
  app.add_option("--dataset", dataset, "dataset folder of the training run")->required();
  app.add_option("--labels", labels, "labelled poses (TUM), timestamps equal to frame timestamps")
      ->required();
  app.add_option("--out", out, "map file to write")->required();
  app.add_option("--config", config_path,
                 "firmware config whose colour thresholds to use (default: built-in)");
  app.add_option("--unlabelled", unlabelled,
                 "number of unlabelled frames (default: --ratio x labelled)");
  app.add_option("--ratio", ratio, "unlabelled per labelled frame when --unlabelled is not given")
      ->capture_default_str();
  app.add_option("--boards", boards_text,
                 "feature boards, 1-based, comma separated (e.g. 1,2,5; default: all)");
  app.add_option("--folds", folds, "cross-validation folds")
      ->capture_default_str()
      ->check(CLI::Range(2, 64));
  app.add_flag("--quiet", quiet, "print only the result line");
  CLI11_PARSE(app, argc, argv);

  try {
    const firmware::FirmwareConfig config =
        config_path.empty() ? firmware::default_config() : firmware::load_config(config_path);
    sim_host::TrainOptions opt;
    opt.dataset_dir = dataset;
    opt.labels_path = labels;
    opt.thresholds = config.thresholds;
    opt.unlabelled = unlabelled;
    opt.unlabelled_ratio = ratio;
    opt.folds = folds;
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
    std::ofstream f(out, std::ios::binary);
    f.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
    if (!f) throw std::runtime_error(out + ": cannot write");
    if (!quiet) {
      std::string names;
      for (std::size_t k = 0; k < map.model.feature_count; ++k) {
        names += (k ? " " : "") + config.board_names.names[map.model.board_index[k]];
      }
      std::printf(
          "frames        %zu (%zu without any board in view); labels matched %zu, unmatched %zu\n",
          r.frames, r.empty_frames, r.labelled, r.labels_unmatched);
      std::printf("samples       %zu labelled + %zu unlabelled (ratio 1:%.1f), features: %s\n",
                  r.labelled, r.unlabelled,
                  static_cast<double>(r.unlabelled) / static_cast<double>(r.labelled),
                  names.c_str());
      std::printf("x axis        sigma %.4g, gamma %.3g  (%d-fold CV RMSE %.2f cm)\n", r.x.sigma,
                  r.x.gamma, folds, 100.0 * r.x.cv_rmse_m);
      std::printf("y axis        sigma %.4g, gamma %.3g  (%d-fold CV RMSE %.2f cm)\n", r.y.sigma,
                  r.y.gamma, folds, 100.0 * r.y.cv_rmse_m);
      std::printf(
          "known place   nearest training sample within %.3g (feature units: %% of frame)\n",
          r.known_place_bound);
      std::printf("time          segmentation %.0f ms, training %.0f ms\n", r.segment_ms,
                  r.train_ms);
    }
    std::printf("wrote %s (%zu bytes, %u samples)\n", out.c_str(), bytes.size(),
                map.model.sample_count);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "harmoloc-train: %s\n", e.what());
    return 2;
  }
  return 0;
}
