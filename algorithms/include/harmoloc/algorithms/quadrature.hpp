#pragma once
/// @file 4x quadrature decoding of one encoder's A/B lines from per-line edge events, with an
/// optional software debounce. Pure logic (no I/O): the libgpiod driver feeds it the kernel's
/// edge events; the unit tests feed it hand-made sequences.
///
/// States (A, B) in the order 00 -> 10 -> 11 -> 01 -> 00 count +1 each step ("forward": A leads
/// B by a quarter period), the reverse order -1. A change of both lines at once is impossible
/// for a quadrature encoder: it means edges were lost, is counted as a glitch and moves the
/// count by nothing. An edge that leaves its line where it already was (a missed edge between
/// two edges of the same direction) is a glitch as well.
///
/// Debounce: an edge is committed only once its line has stayed at the new level for
/// debounce_ns; an edge that goes back within that time cancels it (contact bounce on a
/// mechanical encoder). With debounce_ns = 0 every edge is committed at once.

#include <cstdint>

namespace harmoloc::algorithms {

/// Count change for a transition between two AB states: +1, -1, 0 (no change) or 2 (impossible:
/// both lines changed). Index: (from << 2) | to, state = (A << 1) | B.
inline int quadrature_step(std::uint8_t from_ab, std::uint8_t to_ab) {
  // from\to   00  01  10  11
  static constexpr std::int8_t kTable[16] = {0,  -1, 1,  2,   // 00
                                             1,  0,  2,  -1,  // 01
                                             -1, 2,  0,  1,   // 10
                                             2,  1,  -1, 0};  // 11
  return kTable[((from_ab & 3U) << 2U) | (to_ab & 3U)];
}

class QuadratureDecoder {
 public:
  static constexpr std::uint8_t kLineA = 0;
  static constexpr std::uint8_t kLineB = 1;

  /// Starts at the lines' current levels (read from the device at start-up).
  void reset(bool a, bool b, std::uint64_t debounce_ns = 0) {
    state_ = static_cast<std::uint8_t>((a ? 2U : 0U) | (b ? 1U : 0U));
    debounce_ns_ = debounce_ns;
    pending_[0] = pending_[1] = Pending{};
  }

  /// One edge event: @p line (kLineA or kLineB) is now at @p level since @p timestamp_ns.
  /// Events must come in time order.
  void edge(std::uint8_t line, bool level, std::uint64_t timestamp_ns) {
    line &= 1U;
    commit_until(timestamp_ns);
    if (debounce_ns_ == 0) {
      apply(line, level);
      return;
    }
    Pending& p = pending_[line];
    if (p.active) {
      if (level == line_level(line)) {
        p.active = false;  // bounced back within the window: nothing happened
        ++bounces_;
      } else {
        ++bounces_;  // a repeated edge in the same direction: the level is still settling
        p.timestamp_ns = timestamp_ns;
      }
      return;
    }
    if (level == line_level(line)) {
      ++glitches_;  // an edge that changes nothing: the opposite edge was lost
      return;
    }
    p = Pending{true, level, timestamp_ns};
  }

  /// Commits the edges that have been stable for the debounce time by @p now_ns.
  void commit_until(std::uint64_t now_ns) {
    for (;;) {
      int oldest = -1;
      for (int l = 0; l < 2; ++l) {
        const Pending& p = pending_[l];
        if (p.active && p.timestamp_ns + debounce_ns_ <= now_ns &&
            (oldest < 0 || p.timestamp_ns < pending_[oldest].timestamp_ns)) {
          oldest = l;
        }
      }
      if (oldest < 0) return;
      pending_[oldest].active = false;
      apply(static_cast<std::uint8_t>(oldest), pending_[oldest].level);
    }
  }

  /// Compares the decoded state with the lines' real levels (read after draining every event)
  /// and takes the real levels if they differ: edges were lost on the way (an event queue that
  /// overflowed). A one-step difference is counted (its direction is known); a two-step one is a
  /// glitch. Call only when no edge is pending.
  void resync(bool a, bool b) {
    const auto real = static_cast<std::uint8_t>((a ? 2U : 0U) | (b ? 1U : 0U));
    if (pending_[0].active || pending_[1].active || real == state_) return;
    const int step = quadrature_step(state_, real);
    if (step == 2) {
      ++glitches_;
    } else {
      position_ += step;
      ++resyncs_;
    }
    state_ = real;
  }

  std::int64_t position() const { return position_; }
  std::uint64_t glitches() const { return glitches_; }
  std::uint64_t bounces() const { return bounces_; }
  std::uint64_t resyncs() const { return resyncs_; }
  std::uint8_t state() const { return state_; }
  bool pending() const { return pending_[0].active || pending_[1].active; }

 private:
  struct Pending {
    bool active = false;
    bool level = false;
    std::uint64_t timestamp_ns = 0;
  };

  bool line_level(std::uint8_t line) const {
    return ((state_ >> (line == kLineA ? 1U : 0U)) & 1U) != 0;
  }

  void apply(std::uint8_t line, bool level) {
    const std::uint8_t bit = line == kLineA ? 2U : 1U;
    const auto next = static_cast<std::uint8_t>(level ? (state_ | bit) : (state_ & ~bit & 3U));
    if (next == state_) {
      ++glitches_;  // same level again: the edge in between was lost
      return;
    }
    position_ += quadrature_step(state_, next);  // one line changed: always +-1
    state_ = next;
  }

  std::uint8_t state_ = 0;
  std::uint64_t debounce_ns_ = 0;
  Pending pending_[2]{};
  std::int64_t position_ = 0;
  std::uint64_t glitches_ = 0;
  std::uint64_t bounces_ = 0;
  std::uint64_t resyncs_ = 0;
};

/// Counts frames lost between consecutive sequence numbers of a camera (32-bit, wrapping).
class SequenceGapCounter {
 public:
  /// Returns how many frames were skipped before @p sequence.
  std::uint32_t next(std::uint32_t sequence) {
    std::uint32_t gap = 0;
    if (have_) {
      const std::uint32_t step = sequence - last_;  // modulo 2^32
      // A step of 0 or a huge one (the sequence went back: the stream restarted) is no loss.
      if (step >= 1U && step <= kMaxGap) gap = step - 1U;
    }
    last_ = sequence;
    have_ = true;
    dropped_ += gap;
    return gap;
  }
  /// The stream restarted (device reopened): the next number starts a new run.
  void restart() { have_ = false; }
  std::uint64_t dropped() const { return dropped_; }

  static constexpr std::uint32_t kMaxGap = 1U << 20;

 private:
  std::uint32_t last_ = 0;
  bool have_ = false;
  std::uint64_t dropped_ = 0;
};

}  // namespace harmoloc::algorithms
