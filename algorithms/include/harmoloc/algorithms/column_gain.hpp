#pragma once
/// @file How a board's pixel area depends on its column in the frame (map format 13), and its fit
/// from the training run.
///
/// Seen from one place, a board covers more or fewer pixels at the side of the frame than at the
/// centre: projection stretches the side, a barrel lens squeezes it, vignetting and the colour
/// windows drop its dim pixels. A turn of a few degrees moves every board's column, so the raw
/// areas, and the harmonic fix made from them, change with the heading even where the place does
/// not. The harmonic features are therefore each board's area divided by G(t), t the board's
/// centroid column as an offset from the frame's centre in frame widths:
///
///     G(t) = exp(c2 t^2 + c4 t^4)      (G(0) = 1; even, as a lens is)
///
/// c2 and c4 are measured on the training run itself, from pairs of frames its passes took at the
/// same place and nearly the same heading: there a board's area ratio between the two frames is
/// G(t_1) / G(t_2), so log(A_1 / A_2) is linear in (t_1^2 - t_2^2, t_1^4 - t_2^4) with no
/// intercept (docs/training.md, "The column gain").

#include <cstddef>

#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

/// The gain may be at most this far from 1 anywhere in the frame (a factor either way); a fit
/// beyond it is not a lens but a bad fit, and a map with it is refused.
constexpr double kMaxColumnGain = 4.0;

struct ColumnGain {
  float c2 = 0.0F;
  float c4 = 0.0F;
  /// Both 0: the features are the plain areas (maps before version 13, maps trained without
  /// --column-gain, runs without columns).
  bool present() const { return c2 != 0.0F || c4 != 0.0F; }
  /// G(@p t) for a centroid @p t frame widths from the centre.
  double at(double t) const;
};

/// Board @p board's centroid column as an offset from the frame's centre, in frame widths
/// (-0.5 at the left edge, 0.5 at the right). Meaningful only when @p areas measured columns and
/// the board has pixels.
double column_offset(const AreaVector& areas, std::size_t board);

/// A column @p u_px of a frame @p width_px wide as the same offset (0 when the width is 0).
double column_offset(double u_px, std::uint32_t width_px);

/// @p feature (board @p board's area feature in @p areas) divided by @p gain at the board's
/// column; @p feature unchanged without a gain, without columns or without pixels.
float remove_column_gain(const ColumnGain& gain, const AreaVector& areas, std::size_t board,
                         float feature);

/// The largest |log G(t)| over the frame (|t| <= 0.5).
double column_gain_log_extent(double c2, double c4);

/// Whether (@p c2, @p c4) keeps G within [1 / kMaxColumnGain, kMaxColumnGain] over the frame
/// (false for NaN or infinity).
bool column_gain_in_range(double c2, double c4);

/// The least-squares fit of the gain over pairs of frames taken at one place and heading.
/// Accumulates in double; no allocation.
class ColumnGainFit {
 public:
  /// Adds one pair: every board that gives a bearing in both frames (whole, large enough;
  /// forward_map.hpp's gives_bearing) is one observation. Boards [0, @p boards).
  void add_pair(const AreaVector& first, const AreaVector& second, std::size_t boards);
  std::size_t pairs() const { return pairs_; }
  std::size_t observations() const { return observations_; }
  /// The fitted gain into @p out; false (and @p out the plain areas) with fewer than
  /// @p min_observations observations, a singular fit (every board at one column), or a gain
  /// outside [1 / kMaxColumnGain, kMaxColumnGain].
  bool solve(std::size_t min_observations, ColumnGain& out) const;

 private:
  double s22_ = 0.0, s24_ = 0.0, s44_ = 0.0, r2_ = 0.0, r4_ = 0.0;
  std::size_t pairs_ = 0, observations_ = 0;
};

}  // namespace harmoloc::algorithms
