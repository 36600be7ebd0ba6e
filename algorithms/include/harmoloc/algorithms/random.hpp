#pragma once
/// @file Deterministic random numbers: the same seed gives the same stream on every platform
/// (std:: distributions do not promise that across standard libraries).

#include <cmath>
#include <cstdint>

namespace harmoloc::algorithms {

/// PCG32 (O'Neill, pcg-random.org), XSH-RR output, 64-bit state.
class Pcg32 {
 public:
  explicit Pcg32(std::uint64_t seed = 0x853c49e6748fea9bULL,
                 std::uint64_t stream = 0xda3e39cb94b95bdbULL) {
    reseed(seed, stream);
  }
  void reseed(std::uint64_t seed, std::uint64_t stream = 0xda3e39cb94b95bdbULL) {
    state_ = 0U;
    increment_ = (stream << 1U) | 1U;
    next_u32();
    state_ += seed;
    next_u32();
    has_spare_ = false;
  }
  std::uint32_t next_u32() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + increment_;
    const auto xorshifted = static_cast<std::uint32_t>(((old >> 18U) ^ old) >> 27U);
    const auto rot = static_cast<std::uint32_t>(old >> 59U);
    return (xorshifted >> rot) | (xorshifted << ((32U - rot) & 31U));
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next_u32()) * (1.0 / 4294967296.0); }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Standard normal (Marsaglia polar method; bounded in practice, ~1.27 draws per pair).
  double normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u = 0.0, v = 0.0, s = 0.0;
    do {
      u = 2.0 * uniform() - 1.0;
      v = 2.0 * uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double k = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * k;
    has_spare_ = true;
    return u * k;
  }
  double normal(double mean, double stddev) { return mean + stddev * normal(); }

 private:
  std::uint64_t state_ = 0;
  std::uint64_t increment_ = 1;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace harmoloc::algorithms
