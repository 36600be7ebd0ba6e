#pragma once
/// @file How wrong the harmonic fix has been where it names a place: per training sample, the
/// error of the training run's cross-validated fixes that landed near the sample's place. Where
/// a place's areas look like another place's, the fixes that name it are often wrong, and a
/// global fix error understates it there (docs/filter.md, "The fix term"). Offline (Eigen).

#include <cstddef>
#include <vector>

#include "harmoloc/algorithms/kernel_selection.hpp"

namespace harmoloc::algorithms {

struct LocalFixErrorOptions {
  /// Fixes within this distance of a sample's place count for it (metres; > 0).
  double radius_m = 0.05;
  /// Fewer fixes than this near a sample: it takes @p fallback_m instead.
  std::size_t min_fixes = 3;
  double fallback_m = 0.0;
};

/// For each row of @p sample_xy (m x 2, metres): the RMS per axis of the errors of those
/// held-out fixes that landed within options.radius_m of it. @p fix_xy (n x 2) is where each fix
/// landed, @p error_x_m and @p error_y_m its error against the truth (one per row).
std::vector<double> local_fix_errors(const Eigen::MatrixXd& sample_xy,
                                     const Eigen::MatrixXd& fix_xy,
                                     const std::vector<double>& error_x_m,
                                     const std::vector<double>& error_y_m,
                                     const LocalFixErrorOptions& options);

/// Where the cross-validated fixes of @p selection landed: each error's query place plus the
/// error (KernelSelection::query_row names the query).
Eigen::MatrixXd cross_validated_fixes(const KernelSelection& selection,
                                      const PlacedSamples& queries);

}  // namespace harmoloc::algorithms
