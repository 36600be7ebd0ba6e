#pragma once
/// @file hal::WheelEncoders from two quadrature encoders on GPIO lines (libgpiod 1.6, v1 API):
/// both-edge events on each wheel's A and B lines, merged in timestamp order and decoded 4x
/// (algorithms/quadrature.hpp), impossible transitions counted as glitches, optional software
/// debounce.
///
/// Who reads the events (`reader`):
/// - kThread (default): a reader thread blocks in ppoll() on the four event descriptors and
///   decodes each edge as it comes; the cycle takes the counts through a sequence lock made of
///   atomics (the writer never waits, the reader retries a bounded number of times, nothing
///   allocates). The kernel keeps only 16 events a line (v1 API), so reading them as they come
///   is what lets a wheel turn faster than 16 edges a cycle.
/// - kCycle: no thread; read() drains the events without blocking, once a cycle. Simpler and
///   fully deterministic, but a line with more than 16 edges in one cycle loses events (seen as
///   glitches and resynchronised): for slow wheels and for tests.
///
/// Lost events are found by comparing the decoded state with the lines' real levels when the
/// lines have been quiet twice in a row; a one-step difference is taken as a count, a two-step one
/// is a glitch. Counts are 64-bit inside and reported modulo 2^32 (counter_bits = 32).

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "harmoloc/algorithms/quadrature.hpp"
#include "harmoloc/drivers/count_handoff.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

struct gpiod_chip;
struct gpiod_line;

namespace harmoloc::drivers {

enum class GpioReader : std::uint8_t { kThread = 0, kCycle = 1 };

struct GpioEncoderOptions {
  std::string chip = "gpiochip0";  ///< name, path, label or number (gpiod_chip_open_lookup)
  std::array<unsigned, 2> left_lines{0, 1};   ///< A, B
  std::array<unsigned, 2> right_lines{2, 3};  ///< A, B
  std::uint32_t debounce_us = 0;
  GpioReader reader = GpioReader::kThread;
};

class GpioQuadratureEncoders final : public hal::WheelEncoders {
 public:
  GpioQuadratureEncoders() = default;
  ~GpioQuadratureEncoders();
  GpioQuadratureEncoders(const GpioQuadratureEncoders&) = delete;
  GpioQuadratureEncoders& operator=(const GpioQuadratureEncoders&) = delete;

  /// Opens the chip, requests the four lines for both-edge events, reads their levels and, in
  /// thread mode, starts the reader. Returns an empty string on success, else one line.
  std::string open(const GpioEncoderOptions& options);

  /// The counts as of now, timestamped @p data_time_ns (a GPIO counter is always current);
  /// kNoData only when the lines failed.
  hal::EncoderStatus read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) override;
  hal::EncoderCounters counters() const override;

  /// Signed 64-bit positions, for tests and diagnostics.
  std::int64_t left_position() const;
  std::int64_t right_position() const;
  const std::string& description() const { return description_; }

 private:
  static constexpr std::size_t kLines = 4;  // left A, left B, right A, right B
  /// One pass over the lines: read what is waiting (non-blocking), decode, publish.
  /// Returns false when a line failed.
  bool service(std::uint64_t now_ns);
  void publish();
  void reader_loop();
  void close_all();

  GpioEncoderOptions options_;
  gpiod_chip* chip_ = nullptr;
  std::array<gpiod_line*, kLines> lines_{};
  std::array<int, kLines> fds_{-1, -1, -1, -1};
  std::array<algorithms::QuadratureDecoder, 2> decoders_{};
  std::array<int, 2> quiet_mismatch_{};  ///< quiet passes in a row with levels != decoded state
  bool failed_ = false;
  std::uint64_t overflows_ = 0;  ///< lost edges found by the level check (resynchronised)
  std::string description_;

  // Hand-off to the cycle (a sequence lock of atomics, count_handoff.hpp).
  CountHandoff shared_;

  int stop_fd_ = -1;  ///< eventfd that wakes the reader to stop
  std::thread reader_;
  std::uint64_t samples_ = 0;
};

}  // namespace harmoloc::drivers
