#include "harmoloc/algorithms/harmonic_model.hpp"

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

}  // namespace harmoloc::algorithms
