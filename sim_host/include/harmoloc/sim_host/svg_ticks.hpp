#pragma once
/// @file Axis scales and tick steps for the SVG plots: steps are 1, 2 or 5 times a power of ten,
/// so that tick labels are round numbers.

#include <string>
#include <vector>

namespace harmoloc::sim_host::svg {

/// Linear map of a value range onto a pixel range.
struct Scale {
  double v0 = 0.0;
  double v1 = 1.0;
  double p0 = 0.0;
  double p1 = 1.0;
  double operator()(double v) const { return p0 + (v - v0) * (p1 - p0) / (v1 - v0); }
};

/// The 1-2-5 step nearest to @p range / @p target (about @p target intervals, a few more or
/// fewer). 1 for an empty or non-finite range.
double nice_step(double range, int target);

/// The smallest 1-2-5 step that covers @p range in at most @p max_intervals steps. The search
/// starts at the power of ten below @p range / @p magnitude_intervals; line_chart's x axis
/// passes 8 there, which its charts have always used (a different start can land on a
/// neighbouring step through rounding). A range <= 0 gives 1.
double covering_step(double range, double max_intervals, double magnitude_intervals);
inline double covering_step(double range, double max_intervals) {
  return covering_step(range, max_intervals, max_intervals);
}

/// Decimals that show a step of @p step exactly (0..6).
int decimals_for(double step);

/// The multiples of @p step within [lo, hi] (at most 200); -0 prints as 0.
std::vector<double> ticks_in(double lo, double hi, double step);

struct Tick {
  double px;
  std::string label;
};

/// Ticks every @p step over the scale's value range, labelled in units of @p divisor (1000
/// turns microseconds into milliseconds) with the decimals the step needs.
std::vector<Tick> make_ticks(const Scale& scale, double step, double divisor = 1.0);

}  // namespace harmoloc::sim_host::svg
