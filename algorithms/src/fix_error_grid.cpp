#include "harmoloc/algorithms/fix_error_grid.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace harmoloc::algorithms {

void FixErrorGrid::build(const HarmonicModel& model, const ForwardMap& forward) {
  filled_ = false;
  if (!forward.present() || !has_fix_errors(model)) return;
  // Every stored cell is written below; the rest of the table is never read (nor touched).
  // The samples' order by x: 8 KB on the caller's stack, start-up only, rather than a member
  // that would sit in the cycle object for good.
  std::array<std::uint16_t, HarmonicModel::kMaxSamples> by_x;
  const std::size_t n = model.sample_count;
  for (std::size_t i = 0; i < n; ++i) by_x[i] = static_cast<std::uint16_t>(i);
  const auto x_of = [&model](std::uint16_t i) { return model.target_x_m[i]; };
  std::sort(by_x.begin(), by_x.begin() + static_cast<std::ptrdiff_t>(n),
            [&](std::uint16_t a, std::uint16_t b) {
              return x_of(a) < x_of(b) || (x_of(a) == x_of(b) && a < b);
            });
  const auto* first = by_x.data();
  const auto* last = by_x.data() + n;
  for (std::uint32_t tr = 0; tr < forward.tile_rows; ++tr) {
    for (std::uint32_t tc = 0; tc < forward.tile_columns; ++tc) {
      const std::uint16_t slot = forward.tile_slot[tr * forward.tile_columns + tc];
      if (slot == ForwardMap::kNoTile) continue;
      for (std::uint32_t k = 0; k < ForwardMap::kTileCells; ++k) {
        const std::uint32_t c = tc * ForwardMap::kTileSide + k % ForwardMap::kTileSide;
        const std::uint32_t r = tr * ForwardMap::kTileSide + k / ForwardMap::kTileSide;
        const float x = forward.origin_x_m + static_cast<float>(c) * forward.cell_m;
        const float y = forward.origin_y_m + static_cast<float>(r) * forward.cell_m;
        // Outwards from the cell's x in both directions until the x gap alone exceeds the best
        // distance; ties go to the lower sample index, as in fix_error_near().
        const auto* mid = std::lower_bound(
            first, last, x, [&](std::uint16_t i, float value) { return x_of(i) < value; });
        float best_d2 = std::numeric_limits<float>::infinity();
        std::uint16_t best = 0;
        const auto consider = [&](std::uint16_t i) {
          const float dx = model.target_x_m[i] - x, dy = model.target_y_m[i] - y;
          const float d2 = dx * dx + dy * dy;
          if (d2 < best_d2 || (d2 == best_d2 && i < best)) {
            best_d2 = d2;
            best = i;
          }
        };
        for (const auto* p = mid; p != last; ++p) {
          const float dx = x_of(*p) - x;
          if (dx * dx > best_d2) break;
          consider(*p);
        }
        for (const auto* p = mid; p != first;) {
          --p;
          const float dx = x - x_of(*p);
          if (dx * dx > best_d2) break;
          consider(*p);
        }
        error_m_[static_cast<std::size_t>(slot) * ForwardMap::kTileCells + k] =
            model.fix_error_m[best];
      }
    }
  }
  filled_ = true;
}

float FixErrorGrid::at(const ForwardMap& forward, double x_m, double y_m) const {
  if (!filled_) return 0.0F;
  const std::size_t cell = nearest_stored_cell(locate(forward, x_m, y_m));
  return cell == ForwardMap::kVoidCell ? 0.0F : error_m_[cell];
}

double fix_term_sigma_m(double base_sigma_m, double tempering, float fix_error_here_m) {
  return std::max(base_sigma_m, std::sqrt(tempering) * static_cast<double>(fix_error_here_m));
}

}  // namespace harmoloc::algorithms
