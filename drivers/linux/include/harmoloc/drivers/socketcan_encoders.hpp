#pragma once
/// @file hal::WheelEncoders on SocketCAN: a raw CAN socket filtered in the kernel to the motor
/// controller's frame, read non-blocking and drained every cycle, kernel receive timestamps
/// (SO_TIMESTAMPNS, taken onto CLOCK_MONOTONIC), the frame layout from the config
/// (algorithms/can_encoder_layout.hpp), wrong length or ID ignored and counted, error frames
/// (bus-off among them) counted. Samples wait in a fixed ring until the data clock reaches
/// them, so the cycle sees the encoders as they were at its frame's time.

#include <array>
#include <cstdint>
#include <string>

#include "harmoloc/algorithms/can_encoder_layout.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

struct can_frame;

namespace harmoloc::drivers {

struct SocketCanOptions {
  std::string interface = "can0";
  algorithms::EncoderFrameLayout layout;
  /// true: the kernel passes our ID only (a busy bus costs the cycle nothing); false: every
  /// frame reaches the driver and foreign IDs are counted (diagnostics).
  bool kernel_filter = true;
};

class SocketCanEncoders final : public hal::WheelEncoders {
 public:
  static constexpr std::size_t kRingCapacity = 64;       ///< samples waiting for the data clock
  static constexpr std::size_t kMaxFramesPerRead = 256;  ///< bound on one drain

  SocketCanEncoders() = default;
  ~SocketCanEncoders();
  SocketCanEncoders(const SocketCanEncoders&) = delete;
  SocketCanEncoders& operator=(const SocketCanEncoders&) = delete;

  /// Opens a raw socket on the interface with the filters and timestamps set. Returns an empty
  /// string on success, else one line saying what is wrong.
  std::string open(const SocketCanOptions& options);

  hal::EncoderStatus read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) override;
  hal::EncoderCounters counters() const override { return counters_; }

  /// One received frame (raw SocketCAN form, timestamp on CLOCK_MONOTONIC): decoded, counted,
  /// and queued for the data clock. Public so that tests can drive it without an interface.
  void handle_frame(const can_frame& frame, std::uint64_t timestamp_ns);
  /// Sets the layout without a socket (tests).
  void set_layout(const algorithms::EncoderFrameLayout& layout) { options_.layout = layout; }
  /// The number of samples waiting for the data clock.
  std::size_t pending() const { return ring_size_; }

 private:
  struct Sample {
    std::uint32_t left = 0;
    std::uint32_t right = 0;
    std::uint64_t timestamp_ns = 0;
  };
  void drain();

  SocketCanOptions options_;
  int fd_ = -1;
  std::array<Sample, kRingCapacity> ring_{};
  std::size_t ring_head_ = 0;  ///< oldest
  std::size_t ring_size_ = 0;
  bool down_ = false;  ///< the interface is down or gone: counted once until a frame arrives
  hal::EncoderCounters counters_{};
};

}  // namespace harmoloc::drivers
