// Proof of the static-memory rule: after start-up, the cycle (with the host board's file-backed
// fakes, the serial link and the trajectory writer) makes no heap allocation at all, over
// thousands of cycles and through every health state, while the link brings in garbage and
// signed, unsigned and replayed commands. Every allocation function of the process is
// interposed here and counted while the cycle runs. Eigen's own guard is on meanwhile, as in the
// board mains (EIGEN_RUNTIME_NO_MALLOC; firmware/eigen_guard.hpp), and shown to catch a
// dynamically sized Eigen object.
#include "harmoloc/firmware/eigen.hpp"  // before any other Eigen header

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <malloc.h>
#include <pthread.h>

#include "../unit/mavlink_test_frames.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/dataset/tum_writer.hpp"
#include "harmoloc/drivers/monotonic_clock.hpp"
#include "harmoloc/drivers/record_file.hpp"
#include "harmoloc/drivers/serial_link.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/eigen_guard.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"
#include "harmoloc/firmware/map_loader.hpp"
#include "harmoloc/host/file_camera.hpp"
#include "harmoloc/host/log_encoders.hpp"
#include "run_recording.hpp"
#include "stats_dumper.hpp"

extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);
}

namespace {

std::atomic<bool> g_armed{false};
std::atomic<std::uint64_t> g_allocations{0};
std::atomic<std::size_t> g_first_size{0};
// Counting only the cycle's thread: the stats-on-request writer thread allocates by design (it
// builds the JSON); the cycle that hands it a snapshot must not.
std::atomic<bool> g_cycle_thread_only{false};
pthread_t g_cycle_thread{};

void count(std::size_t size) {
  if (!g_armed.load(std::memory_order_relaxed)) return;
  if (g_cycle_thread_only.load(std::memory_order_relaxed) &&
      pthread_equal(pthread_self(), g_cycle_thread) == 0)
    return;
  if (g_allocations.fetch_add(1) == 0) g_first_size = size;
}

}  // namespace

extern "C" {
void* malloc(std::size_t size) {
  count(size);
  return __libc_malloc(size);
}
void* calloc(std::size_t n, std::size_t size) {
  count(n * size);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  count(size);
  return __libc_realloc(p, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  count(size);
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  count(size);
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  count(size);
  *out = __libc_memalign(alignment, size);
  return *out == nullptr ? ENOMEM : 0;
}
void free(void* p) {
  __libc_free(p);
}
}

void* operator new(std::size_t size) {
  void* p = malloc(size);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void operator delete(void* p) noexcept {
  free(p);
}
void operator delete[](void* p) noexcept {
  free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  free(p);
}

namespace {

using namespace harmoloc;

algorithms::MapFile g_map;

std::string work_dir() {
  const char* w = std::getenv("HARMOLOC_E2E_WORK");
  return w != nullptr ? w : "";
}

struct PassResult {
  std::uint64_t cycles = 0;
  std::uint64_t allocations = 0;
  std::size_t first_size = 0;
  std::array<std::uint64_t, 5> health{};
  std::uint64_t kidnaps = 0;  ///< re-seeds by the kidnap test (the set-pose commands put the
                              ///< cloud far from where the boards say the robot is)
  bool uses_boards = false;
  bool uses_nearby_test = false, uses_floor_search = false;
  std::size_t fewest_particles = 0, most_particles = 0;  ///< over the run's cycles
  firmware::CycleCounters counters;                      ///< the cycle's own, at the end
};

// kRecording: the run is recorded as `harmoloc --record` does (every board): frame copies into
// the slots, the writer thread's files, the text logs; none of it may allocate either.
// kStatsOnRequest: the stats file is asked for every 300 cycles, as SIGUSR1 does on the Linux
// board (boards/common/stats_dumper.hpp): the cycle's thread takes the snapshots without
// allocating; the writer thread's allocations are not counted.
// kLiveClock: the cycle runs as on a live board (set_live_clock): it measures capture to send
// and reports each heartbeat period's latencies on the link (NAMED_VALUE_FLOAT).
// kFloorSearch: on a floor map, the kidnap test takes its evidence from the search over the
// whole floor (kidnap.floor_search) instead of the harmonic fix; the first seed goes round the
// fix (filter.seed_from_search off).
// kSeedFromSearch: the same, and the first seed waits for the search's first pass and starts on
// its pose and the fix (filter.seed_from_search, the default): the search's slices run before
// the filter exists.
enum class Fault {
  kNone,
  kCameraStallMidRun,
  kNoEncoders,
  kRecording,
  kStatsOnRequest,
  kLiveClock,
  kKldSampling,
  kFloorSearch,
  kSeedFromSearch
};

// A monotonic clock an hour ahead of the recording's first frame: a live board's clock, as far
// as the cycle can tell (every frame's capture to send is positive, below the histogram's top).
class AheadOfTheFramesClock final : public hal::Clock {
 public:
  explicit AheadOfTheFramesClock(std::uint64_t first_frame_ns)
      : offset_ns_(first_frame_ns + 3'600'000'000'000ULL - mono_.now_ns()) {}
  std::uint64_t now_ns() const override { return mono_.now_ns() + offset_ns_; }
  void sleep_until(std::uint64_t) override {}

 private:
  drivers::MonotonicClock mono_;
  std::uint64_t offset_ns_;
};

// The camera delivers nothing for cycles [from, to): its frames are taken and dropped.
class StallingCamera final : public hal::Camera {
 public:
  StallingCamera(hal::Camera& inner, std::uint64_t from, std::uint64_t to)
      : inner_(inner), from_(from), to_(to) {}
  hal::CameraStatus acquire(hal::FrameView& frame, std::uint64_t deadline_ns) override {
    const hal::CameraStatus s = inner_.acquire(frame, deadline_ns);
    ++calls_;
    if (s != hal::CameraStatus::kFrame || calls_ <= from_ || calls_ > to_) return s;
    inner_.release();
    return hal::CameraStatus::kNoFrame;
  }
  void release() override { inner_.release(); }
  hal::CameraCounters counters() const override { return inner_.counters(); }

 private:
  hal::Camera& inner_;
  std::uint64_t from_, to_, calls_ = 0;
};

// What the peer sends during a pass: garbage with every kind of command in it, signed with
// @p key (some unsigned, one replayed), spread over the first hundred or so cycles by the
// per-cycle read limit.
std::vector<std::uint8_t> inbound_traffic(const test::mav::Key& key) {
  namespace tm_ = test::mav;
  std::vector<std::uint8_t> out;
  std::uint32_t x = 12345;
  const auto garbage = [&](std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      x = x * 1103515245U + 12345U;
      out.push_back(static_cast<std::uint8_t>((x >> 16U) % 9 == 0 ? 0xFD : x >> 16U));
    }
  };
  const auto add = [&](const tm_::Bytes& b) { out.insert(out.end(), b.begin(), b.end()); };
  std::uint64_t ts = 1;  // the signing clock starts at 0 here: fresh streams are in the window
  const std::array<float, 7> none{};
  for (int round = 0; round < 4; ++round) {
    garbage(30000);
    add(tm_::command(31011, {0.5F, -0.5F, 0.1F, 0, 0, 0, 0}, 255, 190, &key, ++ts));  // set pose
    garbage(3000);
    const tm_::Bytes relocalize = tm_::command(31010, none, 255, 190, &key, ++ts);
    add(relocalize);
    add(relocalize);                                                        // replayed
    add(tm_::command(512, {0, 0, 0, 0, 0, 0, 0}, 255, 190, &key, ++ts));    // HEARTBEAT now
    add(tm_::command(512, {331, 0, 0, 0, 0, 0, 0}, 255, 190, &key, ++ts));  // ODOMETRY now
    add(tm_::command(512, {42, 0, 0, 0, 0, 0, 0}, 255, 190, &key, ++ts));   // denied
    add(tm_::command(400, none, 255, 190, &key, ++ts));                     // unsupported
    add(tm_::command(31010, none));                                         // unsigned
    add(tm_::command(31010, none, 42, 190, &key, ++ts));                    // other source
    add(tm_::frame(0, {0, 0, 0, 0, 6, 8, 0, 0, 3}));                        // ignored
  }
  // Last, a set pose alone, far from where the boards say the robot is: the kidnap test notices
  // and re-seeds the filter around the harmonic fix (under the counting allocator too).
  garbage(30000);
  add(tm_::command(31011, {0.5F, -0.5F, 0.1F, 0, 0, 0, 0}, 255, 190, &key, ++ts));
  return out;
}

// The first frame's timestamp from the dataset's frame index (timestamp_ns,file).
std::uint64_t first_frame_ns(const std::string& dataset, const dataset::DatasetMetadata& meta) {
  std::ifstream in(std::filesystem::path(dataset) / meta.frames_index);
  std::string header, line;
  std::getline(in, header);
  std::getline(in, line);
  return std::stoull(line);
}

// One start-up (allowed to allocate) and one run of the cycle over a whole dataset (not).
// @p config_file: the scene's config (a random scene's colour thresholds), else the defaults.
PassResult run_pass(const std::string& dataset, Fault fault, const std::string& config_file = "") {
  const auto meta = dataset::read_metadata(dataset);
  firmware::FirmwareConfig config =
      config_file.empty() ? firmware::default_config() : firmware::load_config(config_file);
  config.kidnap.floor_search = fault == Fault::kFloorSearch || fault == Fault::kSeedFromSearch;
  config.filter.seed_from_search = fault == Fault::kSeedFromSearch;
  config.geometry = meta.geometry;
  config.can_layout = meta.encoder_layout;
  // As the board mains refuse it: a map trained with other thresholds than the config's.
  EXPECT_EQ(firmware::check_map_matches(g_map, config, meta.image_width_px, meta.image_height_px),
            "");
  config.filter.kld_mode =
      fault == Fault::kKldSampling ? firmware::KldMode::kOn : firmware::KldMode::kOff;
  host::FileCamera file_camera(dataset, meta);
  // Frames 100..200 go missing: odometry only for a while, then back to nominal.
  StallingCamera camera(file_camera, fault == Fault::kCameraStallMidRun ? 100 : 0,
                        fault == Fault::kCameraStallMidRun ? 200 : 0);
  std::unique_ptr<host::LogEncoders> encoders =
      fault == Fault::kNoEncoders
          ? std::make_unique<host::LogEncoders>(std::vector<algorithms::CanFrame>{},
                                                config.can_layout)
          : std::make_unique<host::LogEncoders>(
                (std::filesystem::path(dataset) / meta.encoder_log).string(), config.can_layout);
  const std::string out =
      (std::filesystem::temp_directory_path() / ("harmoloc_noalloc_" + std::to_string(::getpid())))
          .string();
  config.link.has_signing_key = true;
  for (std::size_t i = 0; i < config.link.signing_key.size(); ++i)
    config.link.signing_key[i] = static_cast<std::uint8_t>(i * 13 + 1);
  const std::vector<std::uint8_t> traffic = inbound_traffic(config.link.signing_key);
  {
    std::ofstream in(out + ".in", std::ios::binary);
    in.write(reinterpret_cast<const char*>(traffic.data()),
             static_cast<std::streamsize>(traffic.size()));
  }
  drivers::SerialLink link;
  EXPECT_EQ(link.open(out + ".link", config.link.baud), "");
  EXPECT_EQ(link.open_input(out + ".in"), "");
  dataset::TumWriter trajectory;
  EXPECT_TRUE(trajectory.open(out + ".tum"));
  drivers::MonotonicClock clock;
  // The signing state is persisted as on a board (its writer thread started here, at start-up):
  // the cycle renews the high-water mark as its clock runs, without allocating.
  config.link.signing_state_file = out + ".state";
  drivers::RecordFile signing_store;
  signing_store.start(config.link.signing_state_file, 0);
  boards::RunRecording recording;
  if (fault == Fault::kRecording) {
    boards::RecordOptions record;
    record.dir = out + ".rec";
    record.frames.every_n = 3;
    record.frames.wait_for_disk = true;  // all but the last few frames are written while counted
    std::filesystem::remove_all(record.dir);
    dataset::DatasetMetadata recorded = meta;
    EXPECT_EQ(recording.start(record, recorded, config, true, camera, *encoders), "");
  } else {
    EXPECT_EQ(recording.start(boards::RecordOptions{}, meta, config, true, camera, *encoders), "");
  }
  AheadOfTheFramesClock ahead(first_frame_ns(dataset, meta));
  hal::Clock& cycle_clock = fault == Fault::kLiveClock ? static_cast<hal::Clock&>(ahead) : clock;
  auto cycle = std::make_unique<firmware::LocalizationCycle>(
      config, g_map, recording.camera(), recording.encoders(), link, cycle_clock);
  if (fault == Fault::kLiveClock) cycle->set_live_clock(true);
  cycle->restore_signing_state(firmware::mavlink::SigningState{}, &signing_store, 1'000'000);

  boards::StatsDumper stats_dumper;
  firmware::RunCounters run_counters;
  if (fault == Fault::kStatsOnRequest) EXPECT_EQ(stats_dumper.start(out + ".stats.json", true), "");
  std::uint64_t stats_taken = 0;
  bool stats_wanted = false;

  PassResult r;
  r.fewest_particles = cycle->particle_count();
  firmware::forbid_eigen_heap();  // as the board mains do after start-up
  g_allocations = 0;
  g_cycle_thread = pthread_self();
  g_cycle_thread_only = fault == Fault::kStatsOnRequest;
  g_armed = true;
  while (cycle->run_once() == firmware::CycleResult::kRan) {
    ++r.cycles;
    r.fewest_particles = std::min(r.fewest_particles, cycle->particle_count());
    r.most_particles = std::max(r.most_particles, cycle->particle_count());
    const firmware::PoseOutput& pose = cycle->pose();
    if (pose.valid) trajectory.write(pose.data_time_ns, pose.pose);
    recording.after_cycle(*cycle);
    // As the board's loop does: a request the busy writer could not take is made again on the
    // next cycle.
    stats_wanted = fault == Fault::kStatsOnRequest && (stats_wanted || r.cycles % 300 == 0);
    if (stats_wanted && stats_dumper.request(*cycle, run_counters)) {
      stats_wanted = false;
      ++stats_taken;
    }
  }
  // The writer thread wrote under the counting allocator all along; the end of the run (closing,
  // metadata.toml rewritten) may allocate, as the board mains' ends do.
  g_armed = false;
  g_cycle_thread_only = false;
  if (fault == Fault::kStatsOnRequest) {
    stats_dumper.stop();
    EXPECT_GE(stats_taken, 1U);  // how many more depends on how fast the writer thread runs
    EXPECT_EQ(stats_dumper.written(), stats_taken);
    std::ifstream in(out + ".stats.json");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("\"ended\": \"running\""), std::string::npos) << text.substr(0, 200);
    std::filesystem::remove(out + ".stats.json");
  }
  const std::uint64_t recorded_frames = recording.frame_counters().recorded;
  if (fault == Fault::kLiveClock) EXPECT_GT(cycle->capture_to_send().count(), 100U);
  recording.finish(true, stderr);
  signing_store.stop();
  EXPECT_GT(signing_store.durable_tag(), 1'000'000U) << "the signing state was never renewed";
  EXPECT_FALSE(firmware::eigen_heap_allowed());
  firmware::allow_eigen_heap();
  r.allocations = g_allocations;
  r.first_size = g_first_size;
  r.counters = cycle->counters();
  const firmware::mavlink::InboundCounters in = cycle->inbound_counters();
  EXPECT_EQ(in.bytes_in, traffic.size());
  EXPECT_EQ(in.commands_accepted, 17U);  // 4 rounds: set pose, relocalize, 2 requests; a set pose
  EXPECT_EQ(in.commands_refused, 8U);
  EXPECT_EQ(in.rejected_replay, 4U);
  EXPECT_EQ(in.rejected_unsigned, 4U);
  EXPECT_EQ(in.rejected_source, 4U);
  for (std::size_t h = 0; h < r.health.size(); ++h)
    r.health[h] = cycle->counters().cycles_in_health[h];
  r.kidnaps = cycle->counters().kidnaps;
  r.uses_boards = cycle->uses_boards();
  r.uses_nearby_test = cycle->uses_nearby_test();
  r.uses_floor_search = cycle->uses_floor_search();
  EXPECT_TRUE(trajectory.close());
  std::filesystem::remove(out + ".link");
  std::filesystem::remove(out + ".in");
  std::filesystem::remove(out + ".tum");
  std::filesystem::remove(out + ".state");
  if (fault == Fault::kRecording) {
    EXPECT_GT(recorded_frames, 100U);
    EXPECT_TRUE(std::filesystem::exists(out + ".rec/frames/000010.ppm"));
    EXPECT_TRUE(std::filesystem::file_size(out + ".rec/estimate.tum") > 0);
    std::filesystem::remove_all(out + ".rec");
  }
  return r;
}

TEST(StaticMemory, InterposerCountsAllocations) {
  // The counting works (so a zero below means something).
  g_allocations = 0;
  g_armed = true;
  auto* p = new int[16];
  void* q = std::malloc(10);
  std::string s(200, 'x');
  g_armed = false;
  delete[] p;
  std::free(q);
  EXPECT_GE(g_allocations.load(), 3U);
}

volatile double g_sink = 0.0;

// The guard works in this build (RelWithDebInfo: NDEBUG, where Eigen's own eigen_assert is off):
// once forbidden, a dynamically sized Eigen object stops the program with one line; fixed sizes
// never allocate and still work; allowed again, dynamic sizes work again.
TEST(StaticMemoryDeathTest, EigenHeapAfterStartUpIsCaught) {
  ASSERT_TRUE(firmware::eigen_heap_allowed());
  {
    Eigen::VectorXd startup(64);  // start-up may allocate
    startup.setOnes();
    g_sink = startup.sum();
  }
  firmware::forbid_eigen_heap();
  EXPECT_FALSE(firmware::eigen_heap_allowed());
  const Eigen::Matrix<double, 6, 6> fixed = Eigen::Matrix<double, 6, 6>::Identity() * 2.0;
  g_sink = fixed.trace();
  EXPECT_EQ(g_sink, 12.0);
  EXPECT_DEATH(
      {
        Eigen::VectorXd v(64);
        v.setOnes();
        g_sink = v.sum();
      },
      "harmoloc: Eigen: .*heap allocation is forbidden");
  EXPECT_DEATH(
      {
        const Eigen::MatrixXd m = Eigen::MatrixXd::Identity(8, 8);
        g_sink = m.trace();
      },
      "heap allocation is forbidden");
  firmware::allow_eigen_heap();
  Eigen::VectorXd after(64);
  after.setOnes();
  g_sink = after.sum();
  EXPECT_EQ(g_sink, 64.0);
}

TEST(StaticMemory, NoAllocationAfterStartUp) {
  const std::string work = work_dir();
  ASSERT_FALSE(work.empty())
      << "HARMOLOC_E2E_WORK not set (the e2e.setup fixture provides the datasets)";
  ASSERT_EQ(firmware::load_map(work + "/tiny.hmap", g_map), "");

  struct Pass {
    const char* dataset;
    Fault fault;
  };
  const Pass passes[] = {{"test", Fault::kNone},
                         {"wrap16", Fault::kNone},
                         {"test", Fault::kCameraStallMidRun},
                         {"train", Fault::kNone},
                         {"test", Fault::kNoEncoders},
                         {"test", Fault::kRecording},
                         {"test", Fault::kStatsOnRequest},
                         {"test", Fault::kLiveClock},
                         {"test", Fault::kKldSampling}};
  std::uint64_t total = 0, kidnaps = 0;
  std::array<std::uint64_t, 5> health{};
  for (const Pass& pass : passes) {
    const PassResult r = run_pass(work + "/" + pass.dataset, pass.fault);
    EXPECT_EQ(r.allocations, 0U) << "dataset " << pass.dataset << ": " << r.allocations
                                 << " allocations after start-up, the first of " << r.first_size
                                 << " bytes";
    total += r.cycles;
    kidnaps += r.kidnaps;
    EXPECT_TRUE(r.uses_boards) << "the map has a forward model: the per-board update must run";
    for (std::size_t h = 0; h < health.size(); ++h) health[h] += r.health[h];
    const std::size_t capacity = firmware::default_config().filter.particles;
    if (pass.fault == Fault::kKldSampling) {
      // The count adapted (fewer particles once converged), and re-seeds took every one again.
      EXPECT_LT(r.fewest_particles, capacity / 2);
      EXPECT_EQ(r.most_particles, capacity);
      std::printf("KLD-sampling: %zu to %zu particles\n", r.fewest_particles, r.most_particles);
    } else {
      EXPECT_EQ(r.fewest_particles, capacity);
      EXPECT_EQ(r.most_particles, capacity);
    }
    // The stats' particle figures (filter.particles_*) count the same cycles the filter ran.
    const firmware::CycleCounters& c = r.counters;
    ASSERT_GT(c.particle_cycles, 0U);
    EXPECT_LE(c.particle_cycles, r.cycles);
    EXPECT_EQ(c.particles_min, r.fewest_particles);
    EXPECT_EQ(c.particles_max, r.most_particles);
    EXPECT_GE(c.particles_sum, c.particle_cycles * c.particles_min);
    EXPECT_LE(c.particles_sum, c.particle_cycles * c.particles_max);
    if (pass.fault == Fault::kKldSampling)
      EXPECT_LT(c.particles_sum, c.particle_cycles * capacity * 3 / 4) << "few cycles at fewer";
  }
  EXPECT_GE(total, 2000U);
  // Every health state the firmware can be in was exercised.
  EXPECT_GT(health[static_cast<std::size_t>(firmware::Health::kNominal)], 0U);
  EXPECT_GT(health[static_cast<std::size_t>(firmware::Health::kOdometryOnly)], 0U);
  EXPECT_GT(health[static_cast<std::size_t>(firmware::Health::kVisionOnly)], 0U);
  // The kidnap test's re-seeds ran under the counting allocator too.
  EXPECT_GT(kidnaps, 0U);
  std::printf(
      "%llu cycles without an allocation (nominal %llu, odometry-only %llu, vision-only %llu, "
      "%llu kidnap re-seeds)\n",
      static_cast<unsigned long long>(total), static_cast<unsigned long long>(health[1]),
      static_cast<unsigned long long>(health[2]), static_cast<unsigned long long>(health[3]),
      static_cast<unsigned long long>(kidnaps));
}

// The same on a floor map (a random scene's coverage run, trained with bearings): the floor's
// own work in the cycle, the nearby pose test's refinements and draws and the floor search's
// slices, refinements and re-seeds, runs on a roam with kidnaps to anywhere on the floor.
TEST(StaticMemory, NoAllocationAfterStartUpOnAFloor) {
  const std::string work = work_dir();
  ASSERT_FALSE(work.empty())
      << "HARMOLOC_E2E_WORK not set (the static_memory.floor_setup fixture provides the floor)";
  ASSERT_EQ(firmware::load_map(work + "/floor.hmap", g_map), "");
  const std::string roam = work + "/floor-roam";
  const std::string config = work + "/floor-coverage/harmoloc.toml";
  std::uint64_t total = 0, draws = 0, kidnaps = 0;
  for (const Fault fault : {Fault::kNone, Fault::kFloorSearch, Fault::kSeedFromSearch}) {
    const PassResult r = run_pass(roam, fault, config);
    EXPECT_EQ(r.allocations, 0U) << r.allocations << " allocations after start-up on a floor, "
                                 << "the first of " << r.first_size << " bytes";
    EXPECT_TRUE(r.uses_boards);
    EXPECT_TRUE(r.uses_nearby_test) << "a floor map with bearings: the nearby pose test must run";
    EXPECT_EQ(r.uses_floor_search, fault != Fault::kNone);
    total += r.cycles;
    draws += r.counters.nearby_draws;
    if (fault == Fault::kFloorSearch) kidnaps += r.kidnaps;
  }
  EXPECT_GE(total, 1000U);
  // The work that only a floor has ran under the counting allocator: the test drew particles,
  // and the floor search's evidence re-seeded the filter after a carry.
  EXPECT_GT(draws, 0U);
  EXPECT_GT(kidnaps, 0U);
  std::printf(
      "floor: %llu cycles without an allocation (%llu nearby draws, %llu kidnap re-seeds "
      "from the floor search)\n",
      static_cast<unsigned long long>(total), static_cast<unsigned long long>(draws),
      static_cast<unsigned long long>(kidnaps));
}

}  // namespace
