#pragma once
/// @file The map's per-sample fix errors laid over the forward map's cells, once at start-up:
/// the cycle asks how wrong the training run's fixes were near the place a fix names, and answers
/// with one cell's value instead of a pass over every sample (docs/filter.md, "The fix error
/// here").

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/harmonic_model.hpp"

namespace harmoloc::algorithms {

class FixErrorGrid {
 public:
  /// Takes, for every stored cell of @p forward, the fix error of the sample of @p model nearest
  /// to the cell's centre (the same sample fix_error_near() names for that centre). Without
  /// per-sample errors or a forward map every lookup reads 0. Start-up only: it sorts the
  /// samples once (8 KB of indices on the stack) and visits each cell once.
  void build(const HarmonicModel& model, const ForwardMap& forward);

  /// The fix error of the cell nearest to (@p x_m, @p y_m) (metres; 0 outside the stored cells,
  /// where nothing was trained, and when the grid is empty).
  float at(const ForwardMap& forward, double x_m, double y_m) const;

  bool empty() const { return !filled_; }

 private:
  std::array<float, ForwardMap::kMaxCells> error_m_{};
  bool filled_ = false;
};

static_assert(HarmonicModel::kMaxSamples <= 0x10000, "sample indices are 16-bit");

/// The width of the filter's fix term at a place where the training run's fixes were
/// @p fix_error_here_m wrong: the run's own width @p base_sigma_m (already tempered) or that
/// error widened by the same tempering, whichever is wider.
double fix_term_sigma_m(double base_sigma_m, double tempering, float fix_error_here_m);

}  // namespace harmoloc::algorithms
