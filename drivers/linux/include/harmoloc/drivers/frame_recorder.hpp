#pragma once
/// @file Records camera frames into a dataset folder (frames/NNNNNN.ppm or .yuyv and frames.csv,
/// docs/dataset-format.md) without ever making the cycle wait for the disk.
///
/// Every buffer is reserved at start(): a fixed number of frame slots, each the size of one
/// frame. The cycle's offer() copies a frame into a free slot and hands it to a writer thread
/// through a lock-free ring; with no free slot the frame is dropped and counted. The writer thread
/// writes with open/write/close only (no stdio, no heap), so it never allocates either. A write
/// that fails (a full disk, a removed folder) or the size limit stops the recording, never the
/// cycle.

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "harmoloc/drivers/spsc_ring.hpp"
#include "harmoloc/hal/frame.hpp"

namespace harmoloc::drivers {

struct FrameRecorderOptions {
  std::uint32_t every_n = 1;          ///< record every Nth frame the camera delivers (1: all)
  std::uint64_t max_bytes = 0;        ///< stop after this many bytes of frame files (0: no limit)
  std::uint64_t max_duration_ns = 0;  ///< stop after this long from the first frame (0: no limit)
  /// Wait for a free slot instead of dropping the frame: for the host board's unpaced replay
  /// only, whose clock is the data's and loses nothing by waiting. Never on a live board.
  bool wait_for_disk = false;
};

struct FrameRecorderCounters {
  std::uint64_t offered = 0;   ///< frames the camera delivered while recording
  std::uint64_t recorded = 0;  ///< frames written and listed in frames.csv
  std::uint64_t dropped = 0;   ///< frames not recorded: no free slot (the disk was too slow)
  std::uint64_t skipped = 0;   ///< frames left out by every_n
  std::uint64_t bytes = 0;     ///< bytes of frame files written
};

/// Why a recording stopped before the run ended.
enum class RecordingStop : std::uint8_t { kNone = 0, kSizeLimit, kTimeLimit, kWriteFailed };

/// "" (still recording), "size limit", "time limit" or "write failed" (the stats' words).
constexpr const char* recording_stop_name(RecordingStop reason) {
  switch (reason) {
    case RecordingStop::kSizeLimit:
      return "size limit";
    case RecordingStop::kTimeLimit:
      return "time limit";
    case RecordingStop::kWriteFailed:
      return "write failed";
    case RecordingStop::kNone:
      break;
  }
  return "";
}

class FrameRecorder {
 public:
  static constexpr std::size_t kSlots = 8;  ///< frames in flight between the cycle and the disk

  FrameRecorder() = default;
  ~FrameRecorder() { stop(); }
  FrameRecorder(const FrameRecorder&) = delete;
  FrameRecorder& operator=(const FrameRecorder&) = delete;

  /// Start-up: creates DIR/frames/ and DIR/frames.csv, reserves the slots for frames of the
  /// given size and format, and starts the writer thread. Returns "" or one line saying why not.
  std::string start(const std::string& dir, std::uint32_t width_px, std::uint32_t height_px,
                    hal::PixelFormat format, const FrameRecorderOptions& options);
  /// Cycle: copies @p frame (if it is due and a slot is free) for the writer. Never blocks,
  /// never allocates. Frames of another size or format than start() was given are dropped.
  void offer(const hal::FrameView& frame);
  /// Writes what is queued, stops the thread and closes frames.csv. Safe to call twice.
  void stop();

  bool active() const { return started_ && stop_reason() == RecordingStop::kNone; }
  RecordingStop stop_reason() const {
    return static_cast<RecordingStop>(stop_reason_.load(std::memory_order_acquire));
  }
  /// errno of the write that failed, with stop_reason() == kWriteFailed.
  int error() const { return error_.load(std::memory_order_acquire); }
  /// The file whose write failed (empty otherwise); valid after stop().
  const char* failed_path() const { return failed_path_.data(); }
  FrameRecorderCounters counters() const;

  /// For tests: while held, the writer takes nothing from the ring (a disk that stalls).
  /// Holding returns once the writer thread has seen it.
  void hold_writer_for_test(bool hold);

 private:
  struct Slot {
    std::vector<std::uint8_t> bytes;  // reserved at start(): one packed frame
    std::uint64_t timestamp_ns = 0;
  };
  void writer_loop();
  bool write_slot(const Slot& slot);
  void fail(int error, const char* path);

  std::string dir_;
  std::uint32_t width_px_ = 0, height_px_ = 0;
  hal::PixelFormat format_ = hal::PixelFormat::kRgb24;
  std::size_t row_bytes_ = 0;
  FrameRecorderOptions options_;
  std::array<Slot, kSlots> slots_;
  SpscRing<std::uint32_t, kSlots> free_;    // writer -> cycle: slots to fill
  SpscRing<std::uint32_t, kSlots> filled_;  // cycle -> writer: slots to write
  std::thread writer_;
  int index_fd_ = -1;
  bool started_ = false;
  std::atomic<bool> quit_{false};
  std::atomic<bool> hold_{false};
  std::atomic<bool> hold_seen_{false};
  std::atomic<std::uint8_t> stop_reason_{0};
  std::atomic<int> error_{0};
  std::array<char, 1024> failed_path_{};
  // Written by the cycle only.
  std::uint64_t offered_ = 0, skipped_ = 0, first_ns_ = 0;
  std::atomic<std::uint64_t> dropped_{0};
  // Written by the writer only.
  std::atomic<std::uint64_t> recorded_{0}, bytes_{0};
  std::uint64_t file_number_ = 0;
};

}  // namespace harmoloc::drivers
