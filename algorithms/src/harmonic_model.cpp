#include "harmoloc/algorithms/harmonic_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace harmoloc::algorithms {

void areas_to_features(const HarmonicModel& model, const AreaVector& areas,
                       std::array<float, HarmonicModel::kMaxFeatures>& features) {
  features.fill(0.0F);
  for (std::size_t k = 0; k < model.feature_count; ++k) {
    const std::size_t board = model.board_index[k];
    const std::uint32_t px = board < areas.count ? areas.pixels[board] : 0U;
    features[k] = remove_column_gain(model.column_gain, areas, board,
                                     static_cast<float>(px) * model.area_scale);
  }
}

float column_feature(double centroid_column_px, std::uint32_t width_px, float feature) {
  if (!(feature > 0.0F) || width_px < 2) return 0.0F;
  const double u = centroid_column_px / static_cast<double>(width_px - 1U);
  return static_cast<float>((std::clamp(u, 0.0, 1.0) - 0.5) *
                            std::sqrt(static_cast<double>(feature)));
}

bool areas_to_columns(const HarmonicModel& model, const AreaVector& areas,
                      std::array<float, HarmonicModel::kMaxFeatures>& columns) {
  columns.fill(0.0F);
  if (!areas.columns_measured()) return false;
  for (std::size_t k = 0; k < model.feature_count; ++k) {
    const std::size_t board = model.board_index[k];
    if (board < areas.count && areas.pixels[board] > 0)
      columns[k] = column_feature(areas.centroid_column_px(board), areas.width_px,
                                  static_cast<float>(areas.pixels[board]) * model.area_scale);
  }
  return true;
}

float fix_error_near(const HarmonicModel& model, double x_m, double y_m) {
  float best_d2 = std::numeric_limits<float>::infinity();
  float error_m = 0.0F;
  const auto x = static_cast<float>(x_m), y = static_cast<float>(y_m);
  for (std::size_t i = 0; i < model.sample_count; ++i) {
    const float dx = model.target_x_m[i] - x, dy = model.target_y_m[i] - y;
    const float d2 = dx * dx + dy * dy;
    if (d2 < best_d2) {
      best_d2 = d2;
      error_m = model.fix_error_m[i];
    }
  }
  return error_m;
}

bool has_fix_errors(const HarmonicModel& model) {
  return std::any_of(model.fix_error_m.begin(),
                     model.fix_error_m.begin() + static_cast<std::ptrdiff_t>(model.sample_count),
                     [](float e) { return e > 0.0F; });
}

}  // namespace harmoloc::algorithms
