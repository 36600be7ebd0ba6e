#pragma once
/// @file The application every board runs around the cycle: start-up (config, map, link, output
/// files, recording, signing), the run loop with its per-cycle outputs, and the end (outputs
/// closed, stats, summary, exit status; docs/architecture.md). A board main parses its command
/// line, wires its devices (camera, encoders, pacing) and hands them over; nothing here knows
/// which devices they are.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "board_run.hpp"
#include "run_recording.hpp"
#include "stats_dumper.hpp"

#include "harmoloc/dataset/area_log.hpp"
#include "harmoloc/dataset/encoder_csv.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/tum_writer.hpp"
#include "harmoloc/drivers/monotonic_clock.hpp"
#include "harmoloc/drivers/realtime_setup.hpp"
#include "harmoloc/drivers/record_file.hpp"
#include "harmoloc/drivers/serial_link.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/cycle_pacer.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/stats_report.hpp"

namespace harmoloc::boards {

/// A start-up failure: one line on stderr; returns exit status 2.
int fail(const std::string& why);

/// The config's [realtime] set-up applied where permitted (drivers/realtime_setup.hpp).
drivers::RealtimeReport apply_realtime(const firmware::FirmwareConfig& config);

/// What the summary and the end-of-run lines speak of: a replay (the host board: the filter's
/// work) or a live run (the Linux board: the devices' counters and the time it ran).
enum class RunKind : std::uint8_t { kReplay, kLive };

/// What every board's command line may set (each board adds the options with its own help).
struct AppOptions {
  std::string map_path, config_path, link_path, link_in_path, stats_path;
  std::string trajectory_path, fixes_path, areas_path, record_encoders_path;
  RecordOptions record;
  bool quiet = false;
  /// SIGUSR1 writes the stats file (--stats) without stopping (stats_dumper.hpp).
  bool stats_on_request = false;
  /// A run that records (--record, --record-areas) may go without a map.
  bool records() const { return !record.dir.empty() || !areas_path.empty(); }
};

/// What a board adds to the run loop. Every call happens inside the loop, where nothing may
/// allocate.
class BoardLoop {
 public:
  /// Runs one cycle, started as the board paces it.
  virtual firmware::CycleResult run_cycle(firmware::LocalizationCycle& cycle) = 0;
  /// Once, right before the first cycle.
  virtual void started(std::uint64_t /*start_ns*/) {}
  /// After each cycle and its outputs: the reason to stop ("cycle limit", ...) or nullptr.
  virtual const char* after_cycle(const firmware::LocalizationCycle& /*cycle*/,
                                  std::uint64_t /*cycles*/) {
    return nullptr;
  }
  /// Once, after the last cycle.
  virtual void stopping(const char* /*ended*/, std::uint64_t /*cycles*/) {}

 protected:
  ~BoardLoop() = default;
};

class Application {
 public:
  Application(RunKind kind, const AppOptions& options) : kind_(kind), options_(options) {}
  Application(const Application&) = delete;
  Application& operator=(const Application&) = delete;

  // ---- start-up, in this order; each returns "" or one line saying why not ----
  std::string load_config();
  firmware::FirmwareConfig& config() { return config_; }
  /// The map of --map or, for a run that only records, an empty map with the config's
  /// thresholds; either must match the config and the frame size. @p no_map says what to do
  /// when neither applies.
  std::string load_map(std::uint32_t width_px, std::uint32_t height_px, const char* no_map);
  const algorithms::MapFile& map() const { return map_; }
  drivers::MonotonicClock& clock() { return clock_; }
  /// The link on --link or @p default_link, --link-in, and every output file the options name;
  /// --record-encoders records what the cycle reads from @p encoders.
  std::string open_outputs(const std::string& default_link, hal::WheelEncoders& encoders,
                           std::uint32_t width_px, std::uint32_t height_px);
  drivers::SerialLink& link() { return link_; }
  /// The wheel encoders the cycle reads (recorded, with --record-encoders).
  hal::WheelEncoders& encoders();
  /// --record (its folder described by @p recorded), the cycle on @p camera, the link's signing.
  std::string start_cycle(const dataset::DatasetMetadata& recorded, hal::Camera& camera,
                          hal::PixelFormat pixel_format);
  firmware::LocalizationCycle& cycle() { return *cycle_; }
  firmware::CyclePacer& pacer() { return *pacer_; }
  /// For the board to say what it is (board, pacing, wake-up latency, how a run ends by itself).
  firmware::RunCounters& counters() { return run_; }
  /// The start-up summary's lines on what the map sets: the odometry calibration applied, the
  /// route terms dropped for a floor map (none when there is nothing to say).
  void say_map_settings() const;

  // ---- the run ----
  /// Cycles until @p loop ends the run, the cycle ends or a stop signal arrives; each pose goes
  /// to the output files. @p progress_line: the board keeps a line open on stderr.
  void run(BoardLoop& loop, bool progress_line);
  /// Every output closed, the stats written, the summary said; returns the exit status.
  int finish();

 private:
  class OutputWatch {
   public:
    void add(const dataset::BufferedOutput& out) { outputs_[count_++] = Watched{&out, false}; }
    void check();
    /// After the outputs were closed: says what failed at the end; returns how many failed.
    unsigned finish();
    bool progress_line = false;  // "\r  cycle N/M" may be open on stderr

   private:
    struct Watched {
      const dataset::BufferedOutput* out;
      bool reported;
    };
    void report(Watched& w) const;
    Watched outputs_[8]{};
    std::size_t count_ = 0;
  };

  void say_summary() const;
  int exit_status() const;

  RunKind kind_;
  AppOptions options_;
  firmware::FirmwareConfig config_;
  // Fixed capacity (1.8 MB with the forward map's tiles), allocated once and never freed: as a
  // member of a static object it would be initialised data (its thresholds and feature weights
  // default to non-zero), a 1.8 MB image of near-zeros in the executable.
  algorithms::MapFile& map_ = *new algorithms::MapFile();
  drivers::MonotonicClock clock_;
  drivers::SerialLink link_;
  dataset::TumWriter trajectory_, fixes_;
  dataset::AreaLogWriter areas_;
  std::optional<dataset::EncoderRecorder> encoder_recorder_;
  hal::WheelEncoders* encoders_ = nullptr;
  hal::Camera* camera_ = nullptr;
  RunRecording recording_;
  StatsDumper stats_dumper_;
  std::unique_ptr<firmware::LocalizationCycle> cycle_;
  std::optional<firmware::CyclePacer> pacer_;
  drivers::RecordFile signing_store_;
  firmware::RunCounters run_;
  OutputWatch watch_;
  std::uint64_t start_ns_ = 0, end_ns_ = 0;
  bool any_pose_ = false;
};

}  // namespace harmoloc::boards
