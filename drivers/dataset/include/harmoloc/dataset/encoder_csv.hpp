#pragma once
/// @file GPIO encoder recordings (docs/dataset-format.md, "encoders.csv"): the wheel counters as
/// a robot's cycle read them, one sample a line after a fixed header:
///
///     timestamp_ns,left_ticks,right_ticks
///     1767225600000000000,0,0
///     1767225600033333333,27,-3
///
/// Timestamps are whole nanoseconds, strictly increasing; counts are the free-running counters,
/// written signed or unsigned, and must fit the recording's counter width (metadata
/// `[encoders] counter_bits`): -2^(bits-1) .. 2^bits - 1, kept modulo 2^bits. The parser is
/// strict: any other form is an error naming the file and line.
///
/// EncoderRecorder writes such a file from any hal::WheelEncoders (`harmoloc --record-encoders`
/// on the host and the Linux board); GpioLogEncoders (gpio_log_encoders.hpp) replays one.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "harmoloc/dataset/buffered_output.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

namespace harmoloc::dataset {

/// One line of a recording: both counters, already reduced modulo 2^counter_bits.
struct EncoderSample {
  std::uint64_t timestamp_ns = 0;
  std::uint32_t left_ticks = 0;
  std::uint32_t right_ticks = 0;
  bool operator==(const EncoderSample& o) const {
    return timestamp_ns == o.timestamp_ns && left_ticks == o.left_ticks &&
           right_ticks == o.right_ticks;
  }
};

/// The first line of every recording, exactly.
inline constexpr const char* kEncoderCsvHeader = "timestamp_ns,left_ticks,right_ticks";

/// Parses one sample line of @p size bytes (no line end; one trailing '\r' is accepted). On
/// failure returns false and points @p reason at a static message. No allocation.
bool parse_encoder_csv_line(const char* line, std::size_t size, std::uint8_t counter_bits,
                            EncoderSample& sample, const char** reason);

/// Reads a whole recording. Throws std::runtime_error("FILE:LINE: reason") for a bad header or
/// line, a timestamp that does not increase, a count outside the counter width, an empty line
/// inside the file or a file without samples ("FILE: ..." for those not on a line).
/// @p counter_bits: 8..32.
std::vector<EncoderSample> read_encoder_csv(const std::string& path, std::uint8_t counter_bits);

/// Formats @p sample as one line with its '\n' into @p buffer (unsigned counts). Returns the
/// length, or 0 if @p size is too small (64 bytes always suffice). No allocation.
std::size_t format_encoder_csv_line(const EncoderSample& sample, char* buffer, std::size_t size);

/// A hal::WheelEncoders that passes everything through to another one and records every fresh
/// sample it hands out as a line of a GPIO encoder recording. The file and a 64 KiB stdio buffer
/// are set up by open(); read() then formats on the stack and appends without allocating (stdio
/// writes the buffer out when it is full). A sample whose timestamp is not after the last one
/// recorded is not written (counts are absolute, so the next line still carries its travel).
class EncoderRecorder final : public hal::WheelEncoders {
 public:
  explicit EncoderRecorder(hal::WheelEncoders& inner) : inner_(inner) {}
  ~EncoderRecorder() { close(); }
  EncoderRecorder(const EncoderRecorder&) = delete;
  EncoderRecorder& operator=(const EncoderRecorder&) = delete;

  /// Creates (truncates) @p path and writes the header. False if it cannot be written.
  bool open(const std::string& path);
  /// Flushes and closes; false if any write failed. Safe to call twice.
  bool close();
  const BufferedOutput& output() const { return out_; }

  hal::EncoderStatus read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) override;
  hal::EncoderCounters counters() const override { return inner_.counters(); }

  std::uint64_t samples_written() const { return written_; }
  /// The counter width of the samples seen so far (what the recording's metadata must say);
  /// 0 before the first.
  std::uint8_t counter_bits() const { return counter_bits_; }

 private:
  hal::WheelEncoders& inner_;
  BufferedOutput out_;
  bool any_ = false;
  std::uint64_t last_ns_ = 0;
  std::uint64_t written_ = 0;
  std::uint8_t counter_bits_ = 0;
};

}  // namespace harmoloc::dataset
