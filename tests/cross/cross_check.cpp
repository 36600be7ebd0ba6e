// harmoloc-crosscheck: the firmware's whole cycle on fixed inputs (simulated 320x240 frames of
// the default scenario, a synthetic 204-sample map, a robot creeping forward, 1024 particles,
// filter seed 1), printing what it computed every cycle: areas, the harmonic fix, the fused
// pose and its covariance, the health, and a CRC-32 of the MAVLink bytes sent. The ARM builds
// run it under qemu-user and compare_outputs.py compares that with the host build's output
// (docs/cross-build.md: integers exact, floating point within a stated tolerance).
//   harmoloc-crosscheck [CYCLES]
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "bench_fixtures.hpp"
#include "harmoloc/algorithms/crc32.hpp"
#include "harmoloc/firmware/localization_cycle.hpp"

namespace {

using namespace harmoloc;

// Keeps a running CRC-32 of every frame written, like a file would hold them.
class CrcLink final : public hal::PoseLink {
 public:
  hal::LinkWrite write_frame(const std::uint8_t* bytes, std::size_t size) override {
    crc_ = algorithms::crc32(bytes, size, crc_);
    bytes_ += size;
    return hal::LinkWrite::kSent;
  }
  hal::LinkCounters counters() const override { return {}; }
  std::uint32_t crc() const { return crc_; }
  std::size_t bytes() const { return bytes_; }

 private:
  std::uint32_t crc_ = 0;
  std::size_t bytes_ = 0;
};

algorithms::MapFile g_map;

}  // namespace

int main(int argc, char** argv) {
  const long cycles = argc > 1 ? std::strtol(argv[1], nullptr, 10) : 60;
  constexpr std::uint32_t kWidth = 320, kHeight = 240;
  const bench::Frames frames = bench::simulated_frames(kWidth, kHeight, 8);
  bench::synthetic_map(204, kWidth, kHeight, g_map);
  firmware::FirmwareConfig config = firmware::default_config();
  config.thresholds = g_map.thresholds;
  bench::MemoryCamera camera(frames);
  bench::MemoryEncoders encoders;
  CrcLink link;
  bench::StepClock clock;
  auto cycle =
      std::make_unique<firmware::LocalizationCycle>(config, g_map, camera, encoders, link, clock);
  for (long i = 0; i < cycles; ++i) {
    cycle->run_once();
    const firmware::FixOutput& f = cycle->last_fix();
    const firmware::PoseOutput& p = cycle->pose();
    std::printf("%ld areas", i);
    for (std::size_t k = 0; k < f.areas.count; ++k) std::printf(" %u", f.areas.pixels[k]);
    std::printf(" | fix %d %d %.17g %.17g %.17g %.17g", f.present ? 1 : 0,
                f.fix.known_place ? 1 : 0, f.fix.x_m, f.fix.y_m, f.fix.nearest_distance,
                f.fix.dissimilarity);
    std::printf(" | pose %d %d %.17g %.17g %.17g", p.valid ? 1 : 0, static_cast<int>(p.health),
                p.pose.x_m, p.pose.y_m, p.pose.yaw_rad);
    std::printf(" | cov %.17g %.17g %.17g\n", p.covariance.m[0], p.covariance.m[4],
                p.covariance.m[8]);
  }
  std::printf("link %zu bytes crc32 %08x\n", link.bytes(), link.crc());
  return 0;
}
