#include "harmoloc/algorithms/harmonic_model.hpp"

#include <algorithm>
#include <limits>

namespace harmoloc::algorithms {

void areas_to_features(const HarmonicModel& model, const AreaVector& areas,
                       std::array<float, HarmonicModel::kMaxFeatures>& features) {
  features.fill(0.0F);
  for (std::size_t k = 0; k < model.feature_count; ++k) {
    const std::size_t board = model.board_index[k];
    const std::uint32_t px = board < areas.count ? areas.pixels[board] : 0U;
    features[k] = static_cast<float>(px) * model.area_scale;
  }
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

double fix_term_sigma_m(const HarmonicModel& model, double base_sigma_m, double widen, double x_m,
                        double y_m) {
  if (!(widen > 0.0)) return base_sigma_m;
  return std::max(base_sigma_m, widen * static_cast<double>(fix_error_near(model, x_m, y_m)));
}

}  // namespace harmoloc::algorithms
