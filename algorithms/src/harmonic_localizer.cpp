#include "harmoloc/algorithms/harmonic_localizer.hpp"

#include <cmath>
#include <limits>

namespace harmoloc::algorithms {

namespace {

inline float squared_distance(const float* a, const float* b, std::size_t d) {
  float s = 0.0F;
  for (std::size_t k = 0; k < d; ++k) {
    const float t = a[k] - b[k];
    s += t * t;
  }
  return s;
}

// The same over the features whose weight is 1 (the others have 0).
inline float squared_distance(const float* a, const float* b, std::size_t d, const float* weight) {
  float s = 0.0F;
  for (std::size_t k = 0; k < d; ++k) {
    const float t = a[k] - b[k];
    s += weight[k] * (t * t);
  }
  return s;
}

// The local linear fix along one axis: minimise sum_j w_j (t_j - a - b . z_j)^2 + ridge * |b|^2
// over the neighbours, z_j the (weighted) feature differences O_j - O, and return a. The normal
// equations (at most 9 x 9) are accumulated in the kernel's own loop, so each neighbour's weight
// is computed once for the kernel average and the plane alike; solved by Cholesky, fixed size.
class LocalPlane {
 public:
  static constexpr std::size_t kMax = HarmonicModel::kMaxFeatures + 1;

  explicit LocalPlane(std::size_t p) : p_(p) {}

  // One neighbour: weight @p w, z = (1, feature differences), target @p t.
  void add(double w, const std::array<double, kMax>& z, double t) {
    for (std::size_t r = 0; r < p_; ++r) {
      const double wz = w * z[r];
      b_[r] += wz * t;
      for (std::size_t c = 0; c <= r; ++c) a_[r * kMax + c] += wz * z[c];
    }
  }

  // The intercept with @p ridge on the slopes, or @p fallback when the system is not positive
  // definite (relative to @p weight_sum) or the result is not finite.
  double solve(double ridge, double weight_sum, double fallback) {
    for (std::size_t r = 1; r < p_; ++r) a_[r * kMax + r] += ridge;
    for (std::size_t c = 0; c < p_; ++c) {  // Cholesky in place (lower triangle)
      double diag = a_[c * kMax + c];
      for (std::size_t k = 0; k < c; ++k) diag -= a_[c * kMax + k] * a_[c * kMax + k];
      if (!(diag > 1e-12 * weight_sum)) return fallback;
      diag = std::sqrt(diag);
      a_[c * kMax + c] = diag;
      for (std::size_t r = c + 1; r < p_; ++r) {
        double v = a_[r * kMax + c];
        for (std::size_t k = 0; k < c; ++k) v -= a_[r * kMax + k] * a_[c * kMax + k];
        a_[r * kMax + c] = v / diag;
      }
    }
    std::array<double, kMax> y{};
    for (std::size_t r = 0; r < p_; ++r) {
      double v = b_[r];
      for (std::size_t k = 0; k < r; ++k) v -= a_[r * kMax + k] * y[k];
      y[r] = v / a_[r * kMax + r];
    }
    for (std::size_t r = p_; r-- > 0;) {
      double v = y[r];
      for (std::size_t k = r + 1; k < p_; ++k) v -= a_[k * kMax + r] * y[k];
      y[r] = v / a_[r * kMax + r];
    }
    return std::isfinite(y[0]) ? y[0] : fallback;
  }

 private:
  std::size_t p_;
  std::array<double, kMax * kMax> a_{};
  std::array<double, kMax> b_{};
};

// Eq. 9 with the model's feature weights (times @p mask, 0 or 1 per feature, when given), and
// the centroid columns of the features it weighs when the model and @p columns have them. The
// known-place test compares the areas of the features the mask keeps, all of them with equal
// weight, against the sample nearest in that plain distance.
HarmonicFix query(const HarmonicModel& model,
                  const std::array<float, HarmonicModel::kMaxFeatures>& features,
                  const ColumnFeatures* columns, const float* mask, float kernel_scale) {
  HarmonicFix fix;
  const std::size_t n = model.sample_count;
  const std::size_t d = model.feature_count;
  if (n == 0 || d == 0) return fix;
  std::array<float, HarmonicModel::kMaxFeatures> kernel_weight{};
  std::array<float, HarmonicModel::kMaxFeatures> test_weight{};
  bool weighted = false, any_kernel = false;
  for (std::size_t k = 0; k < d; ++k) {
    test_weight[k] = mask == nullptr ? 1.0F : mask[k];
    fix.board_seen = fix.board_seen || (test_weight[k] > 0.0F && features[k] > 0.0F);
    kernel_weight[k] = test_weight[k] * model.feature_weight[k];
    weighted = weighted || kernel_weight[k] != 1.0F;
    any_kernel = any_kernel || kernel_weight[k] > 0.0F;
  }
  // Every feature the kernel would use is masked: the plain features carry the fix.
  if (!any_kernel) kernel_weight = test_weight;
  const bool separate_test = weighted && test_weight != kernel_weight;
  // The centroid columns of the boards the kernel uses, in the kernel's distance only.
  const bool with_columns = columns != nullptr && model.uses_columns();
  std::array<float, HarmonicModel::kMaxFeatures> column_weight{};
  if (with_columns) {
    const float w2 = model.column_weight * model.column_weight;
    for (std::size_t k = 0; k < d; ++k) column_weight[k] = w2 * std::sqrt(kernel_weight[k]);
  }

  // Each distance is computed once and kept (16 KiB of stack at full capacity).
  std::array<float, HarmonicModel::kMaxSamples> d2;  // only the first n are written and read
  float d2_min = std::numeric_limits<float>::infinity();
  float test_min = std::numeric_limits<float>::infinity();
  std::size_t nearest = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float area =
        weighted ? squared_distance(features.data(), model.sample(j), d, kernel_weight.data())
                 : squared_distance(features.data(), model.sample(j), d);
    d2[j] = with_columns ? area + squared_distance(columns->data(), model.sample_columns(j), d,
                                                   column_weight.data())
                         : area;
    if (d2[j] < d2_min) d2_min = d2[j];
    const float t = separate_test
                        ? squared_distance(features.data(), model.sample(j), d, test_weight.data())
                        : area;
    if (t < test_min) {
      test_min = t;
      nearest = j;
    }
  }

  fix.nearest_distance = std::sqrt(static_cast<double>(test_min));
  if (!std::isfinite(d2_min)) return fix;  // distances overflowed: not a place on this map

  double sum_wx = 0.0, sum_wy = 0.0, sum_wx_fx = 0.0, sum_wy_fy = 0.0;
  const float sx = model.sigma_x * kernel_scale;
  const float sy = model.sigma_y * kernel_scale;
  // The local linear correction's plane: over the features the kernel uses, each difference
  // scaled by the square root of its kernel weight.
  const bool linear = model.local_linear_ridge > 0.0F;
  std::array<std::size_t, HarmonicModel::kMaxFeatures> used{};
  std::array<double, HarmonicModel::kMaxFeatures> scale{};
  std::size_t m = 0;
  if (linear) {
    for (std::size_t k = 0; k < d; ++k)
      if (kernel_weight[k] > 0.0F) {
        scale[m] = std::sqrt(static_cast<double>(kernel_weight[k]));
        used[m++] = k;
      }
  }
  LocalPlane plane_x(m + 1), plane_y(m + 1);
  std::array<double, LocalPlane::kMax> z{};
  z[0] = 1.0;
  // A weight below exp(-40) (4e-18 of the nearest sample's) cannot move the sums even with 4096
  // samples; skipping its exp saves most of the query with the narrow kernels training picks.
  constexpr float kNegligible = 40.0F;
  for (std::size_t j = 0; j < n; ++j) {
    const float excess = d2[j] - d2_min;
    const float ex = sx * excess, ey = sy * excess;
    if (ex > kNegligible && ey > kNegligible) continue;
    const double wx = ex > kNegligible ? 0.0 : std::exp(static_cast<double>(-ex));
    const double wy = ey > kNegligible ? 0.0 : std::exp(static_cast<double>(-ey));
    const auto tx = static_cast<double>(model.target_x_m[j]);
    const auto ty = static_cast<double>(model.target_y_m[j]);
    sum_wx += wx;
    sum_wy += wy;
    sum_wx_fx += wx * tx;
    sum_wy_fy += wy * ty;
    const bool near_x = ex <= kLocalLinearCutoff, near_y = ey <= kLocalLinearCutoff;
    if (!linear || !(near_x || near_y)) continue;  // harmonic_localizer.hpp
    const float* s = model.sample(j);
    for (std::size_t i = 0; i < m; ++i)
      z[i + 1] =
          scale[i] * (static_cast<double>(s[used[i]]) - static_cast<double>(features[used[i]]));
    if (near_x) plane_x.add(wx, z, tx);
    if (near_y) plane_y.add(wy, z, ty);
  }
  // The nearest sample has weight 1, so both sums are >= 1.
  fix.x_m = sum_wx_fx / sum_wx;
  fix.y_m = sum_wy_fy / sum_wy;
  if (linear) {
    const auto ridge = static_cast<double>(model.local_linear_ridge);
    fix.x_m = plane_x.solve(ridge * sum_wx / (2.0 * static_cast<double>(sx)), sum_wx, fix.x_m);
    fix.y_m = plane_y.solve(ridge * sum_wy / (2.0 * static_cast<double>(sy)), sum_wy, fix.y_m);
  }

  double diff_sum = 0.0, sum = 0.0;
  const float* near = model.sample(nearest);
  for (std::size_t k = 0; k < d; ++k) {
    if (test_weight[k] == 0.0F) continue;
    diff_sum += std::fabs(static_cast<double>(features[k]) - static_cast<double>(near[k]));
    sum += static_cast<double>(features[k]) + static_cast<double>(near[k]);
  }
  fix.dissimilarity = sum > 0.0 ? diff_sum / sum : 1.0;
  fix.known_place = fix.board_seen && std::isfinite(fix.x_m) && std::isfinite(fix.y_m) &&
                    fix.nearest_distance <= static_cast<double>(model.max_nearest_distance) &&
                    fix.dissimilarity <= static_cast<double>(model.max_dissimilarity);
  return fix;
}

}  // namespace

HarmonicFix harmonic_query(const HarmonicModel& model,
                           const std::array<float, HarmonicModel::kMaxFeatures>& features,
                           const ColumnFeatures* columns) {
  return query(model, features, columns, nullptr, 1.0F);
}

HarmonicFix harmonic_query(const HarmonicModel& model,
                           const std::array<float, HarmonicModel::kMaxFeatures>& features,
                           const FeatureMask& use, const ColumnFeatures* columns) {
  std::array<float, HarmonicModel::kMaxFeatures> weight{};
  std::size_t used = 0;
  float full = 0.0F, kept = 0.0F;
  for (std::size_t k = 0; k < model.feature_count; ++k) {
    weight[k] = use[k] ? 1.0F : 0.0F;
    used += use[k] ? 1U : 0U;
    full += model.feature_weight[k];
    kept += weight[k] * model.feature_weight[k];
  }
  if (used == model.feature_count) return query(model, features, columns, nullptr, 1.0F);
  if (used == 0) return HarmonicFix{};
  // The kernel widths scaled by the weight left over the weight in full, so that the weights
  // keep their spread with fewer features.
  return query(model, features, columns, weight.data(),
               kept > 0.0F ? full / kept
                           : static_cast<float>(model.feature_count) / static_cast<float>(used));
}

bool uncut_features(const HarmonicModel& model, const AreaVector& areas,
                    const std::array<float, HarmonicModel::kMaxFeatures>& features,
                    FeatureMask& use) {
  use.fill(true);
  std::size_t uncut_seen = 0;
  bool any_cut = false;
  for (std::size_t k = 0; k < model.feature_count; ++k) {
    const std::size_t b = model.board_index[k];
    if (!(features[k] > 0.0F)) continue;  // not in view: nothing to cut
    if (b < areas.count && areas.cut_by_side(b)) {
      use[k] = false;
      any_cut = true;
    } else if (model.feature_weight[k] > 0.0F) {
      ++uncut_seen;
    }
  }
  if (!any_cut || uncut_seen >= 2) return any_cut;
  use.fill(true);
  return false;
}

HarmonicFix harmonic_fix(const HarmonicModel& model, const AreaVector& areas,
                         const std::array<float, HarmonicModel::kMaxFeatures>& features,
                         const ColumnFeatures* columns, FeatureMask& use) {
  // Without a cut board the plain query: the same arithmetic, and no kernel widths rescaled.
  if (!uncut_features(model, areas, features, use)) return harmonic_query(model, features, columns);
  HarmonicFix fix = harmonic_query(model, features, use, columns);
  fix.cut_board_left_out = true;
  return fix;
}

}  // namespace harmoloc::algorithms
