#include "harmoloc/algorithms/fix_board_check.hpp"

#include <algorithm>
#include <cmath>

namespace harmoloc::algorithms {

namespace {

std::size_t weighted(const HarmonicModel& model, const FeatureMask& use) {
  std::size_t n = 0;
  for (std::size_t k = 0; k < model.feature_count; ++k)
    n += use[k] && model.feature_weight[k] > 0.0F ? 1U : 0U;
  return n;
}

double distance(const HarmonicFix& fix, double x_m, double y_m) {
  return std::hypot(fix.x_m - x_m, fix.y_m - y_m);
}

}  // namespace

FixCheckParams fix_check_params(double fix_rmse_x_m, double fix_rmse_y_m) {
  FixCheckParams p;
  const double radial = std::hypot(fix_rmse_x_m, fix_rmse_y_m);
  if (!(radial > 0.0)) return p;
  p.far_m = std::max(3.0 * radial, 0.03);
  p.near_m = std::max(1.5 * radial, 0.015);
  return p;
}

void FixBoardCheck::reset() {
  hold_.fill(0);
}

HarmonicFix FixBoardCheck::fix(const HarmonicModel& model,
                               const std::array<float, HarmonicModel::kMaxFeatures>& features,
                               const FeatureMask& use, double x_m, double y_m,
                               const FixCheckParams& params, const ColumnFeatures* columns) {
  const std::size_t n = model.feature_count;
  for (std::size_t k = 0; k < n; ++k) hold_[k] = hold_[k] > 0 ? hold_[k] - 1 : 0;
  // The features the fix may use: those allowed, less the suspects, as long as two remain.
  const auto trusted = [&]() {
    FeatureMask m = use;
    for (std::size_t k = 0; k < n; ++k) m[k] = m[k] && hold_[k] == 0;
    return weighted(model, m) >= 2 ? m : use;
  };
  FeatureMask effective = trusted();
  if (!(params.near_m > 0.0) || weighted(model, use) < kFixCheckMinBoards)
    return harmonic_query(model, features, effective, columns);

  // The next allowed feature the kernel weighs, in turn.
  std::size_t k = n;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t c = (next_ + i) % n;
    if (use[c] && model.feature_weight[c] > 0.0F) {
      k = c;
      break;
    }
  }
  if (k == n) return harmonic_query(model, features, effective, columns);
  next_ = (k + 1) % n;
  FeatureMask with = effective, without = effective;
  with[k] = true;
  without[k] = false;
  if (weighted(model, without) < 2) return harmonic_query(model, features, effective, columns);
  const HarmonicFix a = harmonic_query(model, features, with, columns);
  const HarmonicFix b = harmonic_query(model, features, without, columns);
  const bool a_known = a.known_place && std::isfinite(a.x_m) && std::isfinite(a.y_m);
  const bool b_known = b.known_place && std::isfinite(b.x_m) && std::isfinite(b.y_m);
  if (a_known && b_known && distance(a, x_m, y_m) >= params.far_m &&
      distance(b, x_m, y_m) <= params.near_m) {
    suspicions_ += hold_[k] == 0 ? 1U : 0U;
    hold_[k] = params.hold_frames;
  } else if (hold_[k] > 0 && a_known && distance(a, x_m, y_m) <= params.near_m) {
    hold_[k] = 0;
  }
  effective = trusted();
  if (effective == with) return a;
  if (effective == without) return b;
  return harmonic_query(model, features, effective, columns);
}

}  // namespace harmoloc::algorithms
