// Shared by the fault-injection tests and the soak with faults (tests/fault/): the tiny map, the
// firmware's cycle replayed over injected faults with every cycle recorded, the truth at any
// data time, the link's bytes checked frame by frame, and the process's heap, resident memory and
// open descriptors.
#pragma once

#include <gtest/gtest.h>
#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "harmoloc/drivers/monotonic_clock.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/map_loader.hpp"
#include "harmoloc/firmware/mavlink_parser.hpp"
#include "harmoloc/sim_host/scenario.hpp"
#include "harmoloc/sim_host/scenario_run.hpp"

namespace harmoloc::fault {

namespace hs = harmoloc::sim_host;
namespace ha = harmoloc::algorithms;
namespace hf = harmoloc::firmware;

/// Loads $ENV_VAR/NAME into @p map (a ctest fixture writes it: the e2e fixture tiny.hmap, the
/// scenario fixture desk-shuttle.hmap).
/// Whether the tests check the 15 ms budget itself (HARMOLOC_TIMING_CHECKS=1: a quiet machine,
/// the board). A loaded machine or a sanitizer stretches single cycles, and a test must not fail
/// under load, so by default they do not.
inline bool timing_checks() {
  const char* v = std::getenv("HARMOLOC_TIMING_CHECKS");
  return v != nullptr && v[0] == '1' && v[1] == '\0';
}

inline void load_fixture_map(const char* env_var, const char* name, ha::MapFile& map) {
  const char* work = std::getenv(env_var);
  const std::string path = std::string(work != nullptr ? work : ".") + "/" + name;
  const std::string e = hf::load_map(path, map);
  if (!e.empty()) ADD_FAILURE() << e << " (a ctest fixture writes it: ctest runs it first)";
}

/// The tiny scenario's map (training seed 1), loaded once per process.
inline const ha::MapFile& tiny_map() {
  static const std::unique_ptr<ha::MapFile> m = [] {
    auto out = std::make_unique<ha::MapFile>();
    load_fixture_map("HARMOLOC_E2E_WORK", "tiny.hmap", *out);
    return out;
  }();
  return *m;
}

/// One simulated run in memory with what a dataset's metadata would give the firmware.
struct SimRun {
  SimRun(const char* scenario_name, std::uint64_t seed)
      : scenario(hs::load_scenario(scenario_name)), run(scenario, seed) {}
  explicit SimRun(const hs::Scenario& s, std::uint64_t seed) : scenario(s), run(scenario, seed) {}

  hf::FirmwareConfig config() const {
    hf::FirmwareConfig c = hf::default_config();
    c.geometry = scenario.robot;
    c.can_layout = scenario.can_layout;
    return c;
  }
  double t0_s() const { return static_cast<double>(run.frame_timestamp_ns(0)) * 1e-9; }
  /// Run time (from the first frame) of a data time.
  double run_time_s(std::uint64_t data_time_ns) const {
    return static_cast<double>(data_time_ns - run.frame_timestamp_ns(0)) * 1e-9;
  }
  /// The true pose at a run time (the motion's 1 ms samples).
  ha::Pose2 truth_at(double t_s) const {
    const auto& m = run.motion();
    const double k = std::round(t_s / hs::ScenarioRun::kMotionStep_s);
    const std::size_t i = k <= 0.0 ? 0 : std::min(m.size() - 1, static_cast<std::size_t>(k));
    return m[i].pose;
  }

  hs::Scenario scenario;
  hs::ScenarioRun run;
};

/// Every frame of a run rendered once (RGB24), so that replays spend no time rendering: a cycle's
/// time is then the firmware's own, as with a camera that hands over a mapped buffer.
class FrameCache {
 public:
  explicit FrameCache(hs::ScenarioRun& run)
      : width_(run.scenario().camera.width_px), height_(run.scenario().camera.height_px) {
    const std::size_t bytes = static_cast<std::size_t>(width_) * height_ * 3U;
    pixels_.resize(bytes * run.frame_count());
    std::vector<std::uint8_t> rgb;
    for (std::size_t k = 0; k < run.frame_count(); ++k) {
      run.render(k, rgb);
      std::copy(rgb.begin(), rgb.end(), pixels_.begin() + static_cast<std::ptrdiff_t>(k * bytes));
      stamps_.push_back(run.frame_timestamp_ns(k));
    }
  }
  std::size_t size() const { return stamps_.size(); }
  const std::uint8_t* frame(std::size_t k) const {
    return pixels_.data() + k * static_cast<std::size_t>(width_) * height_ * 3U;
  }
  std::uint64_t stamp(std::size_t k) const { return stamps_[k]; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }

 private:
  std::uint32_t width_, height_;
  std::vector<std::uint8_t> pixels_;
  std::vector<std::uint64_t> stamps_;
};

/// hal::Camera over a FrameCache: the frames in order with their timestamps, then kEnded.
class CachedCamera final : public hal::Camera {
 public:
  explicit CachedCamera(const FrameCache& cache) : cache_(cache) {}
  hal::CameraStatus acquire(hal::FrameView& f, std::uint64_t /*deadline_ns*/) override {
    if (next_ >= cache_.size()) return hal::CameraStatus::kEnded;
    const std::size_t k = next_++;
    f.data = cache_.frame(k);
    f.width_px = cache_.width();
    f.height_px = cache_.height();
    f.stride_bytes = cache_.width() * 3U;
    f.format = hal::PixelFormat::kRgb24;
    f.timestamp_ns = cache_.stamp(k);
    f.sequence = static_cast<std::uint32_t>(k);
    ++counters_.frames;
    return hal::CameraStatus::kFrame;
  }
  void release() override {}
  hal::CameraCounters counters() const override { return counters_; }

 private:
  const FrameCache& cache_;
  std::size_t next_ = 0;
  hal::CameraCounters counters_{};
};

/// The link's bytes in memory (reserved up front), or nowhere.
class MemoryLink final : public hal::PoseLink {
 public:
  explicit MemoryLink(std::size_t reserve_bytes = 0) { bytes_.reserve(reserve_bytes); }
  hal::LinkWrite write_frame(const std::uint8_t* b, std::size_t n) override {
    ++counters_.frames_sent;
    counters_.bytes_sent += n;
    if (bytes_.capacity() >= bytes_.size() + n) bytes_.insert(bytes_.end(), b, b + n);
    return hal::LinkWrite::kSent;
  }
  hal::LinkCounters counters() const override { return counters_; }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  std::vector<std::uint8_t> bytes_;
  hal::LinkCounters counters_{};
};

/// What a byte stream from the link holds, frame by frame (the firmware's own parser, which
/// checks every checksum). A stream of whole frames has no garbage and no checksum error.
struct StreamCheck {
  std::uint64_t frames = 0, odometry = 0, heartbeats = 0, statustexts = 0;
  std::uint64_t garbage_bytes = 0, crc_errors = 0, bad_headers = 0;
  std::uint64_t sequence_gaps = 0;  ///< frames missing between consecutive sequence numbers
  std::uint8_t last_sequence = 0;
  bool any = false;

  void feed(const std::uint8_t* data, std::size_t n) {
    while (n > 0) {
      const std::size_t pushed = parser_.push(data, n);
      data += pushed;
      n -= pushed;
      drain();
      if (pushed == 0 && !parser_.skip_candidate()) break;
    }
  }
  void drain() {
    hf::mavlink::RxFrame f;
    std::size_t work = 1U << 20;
    while (parser_.next(f, work)) {
      ++frames;
      if (f.msg_id == hf::mavlink::kMsgOdometry) ++odometry;
      if (f.msg_id == hf::mavlink::kMsgHeartbeat) ++heartbeats;
      if (f.msg_id == hf::mavlink::kMsgStatustext) ++statustexts;
      if (any) sequence_gaps += static_cast<std::uint8_t>(f.sequence - last_sequence - 1U);
      last_sequence = f.sequence;
      any = true;
      work = 1U << 20;
    }
    garbage_bytes = parser_.counters().garbage_bytes;
    crc_errors = parser_.counters().crc_errors;
    bad_headers = parser_.counters().bad_headers;
  }
  std::size_t unparsed() const { return parser_.buffered(); }

 private:
  hf::mavlink::FrameParser parser_;
};

/// The cycle's clock in these tests: the thread's CPU time, so that the stage times, the budget
/// and the overrun count measure the firmware's own work, not time this shared machine spent
/// running other processes (the replay also records each cycle's wall-clock time: a cycle that
/// waited, on a line that blocks for instance, shows there).
class ThreadCpuClock final : public hal::Clock {
 public:
  std::uint64_t now_ns() const override {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL +
           static_cast<std::uint64_t>(ts.tv_nsec);
  }
  void sleep_until(std::uint64_t) override {}
};

/// Every cycle of a replay.
struct CycleRecord {
  double t_s = 0.0;  ///< data time from the run's first frame
  std::uint64_t data_time_ns = 0;
  hf::PoseOutput pose;
  double error_m = -1.0;          ///< position error against the truth (-1 without a pose)
  double wall_ms = 0.0;           ///< how long run_once() took
  double cpu_ms = 0.0;            ///< of which CPU time of this thread
  bool frame = false;             ///< the cycle had a frame
  std::uint64_t link_frames = 0;  ///< frames the cycle wrote (counted at the link)
};

struct Replay {
  std::vector<CycleRecord> cycles;
  hf::CycleCounters counters;
  hal::CameraCounters camera;
  hal::EncoderCounters encoders;
  hal::LinkCounters link;
  double max_wall_ms = 0.0;  ///< the longest run_once() on the wall clock
  double max_cpu_ms = 0.0;   ///< the longest cycle in CPU time (the firmware's own histogram)

  /// Worst and RMS position error over [from_s, to_s) of the cycles that have a pose.
  struct Errors {
    double max_m = 0.0, rmse_m = 0.0;
    std::size_t cycles = 0;
  };
  Errors errors(double from_s, double to_s) const {
    Errors e;
    double se = 0.0;
    for (const CycleRecord& c : cycles) {
      if (c.t_s < from_s || c.t_s >= to_s || c.error_m < 0.0) continue;
      e.max_m = std::max(e.max_m, c.error_m);
      se += c.error_m * c.error_m;
      ++e.cycles;
    }
    if (e.cycles > 0) e.rmse_m = std::sqrt(se / static_cast<double>(e.cycles));
    return e;
  }
  /// The health at run time @p t_s (the first cycle at or after it).
  hf::Health health_at(double t_s) const {
    for (const CycleRecord& c : cycles)
      if (c.t_s >= t_s - 1e-9) return c.pose.health;
    return cycles.back().pose.health;
  }
  const CycleRecord& at(double t_s) const {
    for (const CycleRecord& c : cycles)
      if (c.t_s >= t_s - 1e-9) return c;
    return cycles.back();
  }
  /// Cycles in [from_s, to_s) whose health is @p h.
  std::size_t cycles_in(hf::Health h, double from_s, double to_s) const {
    std::size_t n = 0;
    for (const CycleRecord& c : cycles)
      if (c.t_s >= from_s && c.t_s < to_s && c.pose.health == h) ++n;
    return n;
  }
  /// Seconds after @p from_s until the health is nominal and the error below @p bound_m, and
  /// both stay so for @p hold_s (or until the end); -1 if never.
  double recovery_s(double from_s, double bound_m, double hold_s) const {
    double good_since = -1.0;
    for (const CycleRecord& c : cycles) {
      if (c.t_s < from_s) continue;
      const bool good =
          c.pose.health == hf::Health::kNominal && c.error_m >= 0.0 && c.error_m < bound_m;
      if (!good) {
        good_since = -1.0;
        continue;
      }
      if (good_since < 0.0) good_since = c.t_s;
      if (c.t_s - good_since >= hold_s) return good_since - from_s;
    }
    return good_since >= 0.0 ? good_since - from_s : -1.0;
  }
};

/// Replays until the camera ends. @p between runs after each cycle (e.g. to drain a pty).
inline Replay replay(const SimRun& sim, const hf::FirmwareConfig& config, hal::Camera& camera,
                     hal::WheelEncoders& encoders, hal::PoseLink& link,
                     const std::function<void(const CycleRecord&)>& between = nullptr,
                     const ha::MapFile& map = tiny_map()) {
  drivers::MonotonicClock clock;
  ThreadCpuClock cpu_clock;
  auto cycle =
      std::make_unique<hf::LocalizationCycle>(config, map, camera, encoders, link, cpu_clock);
  Replay r;
  r.cycles.reserve(sim.run.frame_count() + 16);
  for (;;) {
    const std::uint64_t frames_before = cycle->counters().frames;
    const std::uint64_t link_before = link.counters().frames_sent + link.counters().frames_dropped;
    const std::uint64_t t0 = clock.now_ns();
    const std::uint64_t cpu0 = cpu_clock.now_ns();
    const hf::CycleResult res = cycle->run_once();
    const double wall_ms = static_cast<double>(clock.now_ns() - t0) * 1e-6;
    const double cpu_ms = static_cast<double>(cpu_clock.now_ns() - cpu0) * 1e-6;
    if (res == hf::CycleResult::kEnded) break;
    CycleRecord c;
    c.pose = cycle->pose();
    c.data_time_ns = c.pose.data_time_ns;
    c.t_s = sim.run_time_s(c.data_time_ns);
    c.wall_ms = wall_ms;
    c.cpu_ms = cpu_ms;
    c.frame = cycle->counters().frames != frames_before;
    c.link_frames = link.counters().frames_sent + link.counters().frames_dropped - link_before;
    if (c.pose.valid) {
      const ha::Pose2 truth = sim.truth_at(c.t_s);
      c.error_m = std::hypot(c.pose.pose.x_m - truth.x_m, c.pose.pose.y_m - truth.y_m);
    }
    r.max_wall_ms = std::max(r.max_wall_ms, wall_ms);
    r.cycles.push_back(c);
    if (between) between(r.cycles.back());
  }
  r.counters = cycle->counters();
  r.max_cpu_ms = static_cast<double>(cycle->stage_histogram(hf::Stage::kCycle).max_ns()) * 1e-6;
  r.camera = camera.counters();
  r.encoders = encoders.counters();
  r.link = link.counters();
  return r;
}

// --- the process's resources ---------------------------------------------------------------------

struct Resources {
  long rss_kb = -1;
  std::size_t heap_in_use = 0;  ///< mallinfo2: bytes allocated and not freed (arena + mmap)
  long open_fds = -1;
};

inline Resources resources() {
  Resources r;
  if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
    char line[256];
    while (std::fgets(line, sizeof line, f) != nullptr)
      if (std::strncmp(line, "VmRSS:", 6) == 0) r.rss_kb = std::strtol(line + 6, nullptr, 10);
    std::fclose(f);
  }
  const struct mallinfo2 m = mallinfo2();
  r.heap_in_use = m.uordblks + m.hblkhd;
  std::error_code ec;
  long n = 0;
  for (auto it = std::filesystem::directory_iterator("/proc/self/fd", ec);
       !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
    ++n;
  }
  r.open_fds = ec ? -1 : n - 1;  // the iterator's own descriptor
  return r;
}

}  // namespace harmoloc::fault
