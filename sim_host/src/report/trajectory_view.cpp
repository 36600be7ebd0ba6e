// The view of a trajectory plot (trajectory_plot.cpp, compare_plots.cpp): the bounds, the grid
// step and the poses left out.
#include <algorithm>
#include <cmath>
#include <limits>

#include "plot_kit.hpp"

namespace harmoloc::sim_host {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Box {
  double x0 = kInf, y0 = kInf, x1 = -kInf, y1 = -kInf;
  bool empty() const { return !(x1 >= x0); }
  void add(double x, double y) {
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
  }
  bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
};

}  // namespace

TrajectoryView trajectory_view(
    const std::vector<dataset::StampedPose>& truth,
    const std::vector<const std::vector<dataset::StampedPose>*>& others) {
  // The truth's box, grown to take in the other poses (estimates, fixes) unless they run far
  // away (then they are clipped and counted, so that one wild fix does not shrink the route).
  Box truth_box;
  for (const dataset::StampedPose& p : truth) truth_box.add(p.pose.x_m, p.pose.y_m);
  const double extent = std::max({truth_box.width(), truth_box.height(), 0.2});
  Box limit = truth_box;
  const double grow = 0.5 * extent + 0.5;
  limit.x0 -= grow;
  limit.y0 -= grow;
  limit.x1 += grow;
  limit.y1 += grow;
  Box view = truth_box;
  std::size_t outside = 0;
  const auto take = [&](const std::vector<dataset::StampedPose>& poses) {
    for (const dataset::StampedPose& p : poses) {
      if (limit.contains(p.pose.x_m, p.pose.y_m)) {
        view.add(p.pose.x_m, p.pose.y_m);
      } else {
        ++outside;
      }
    }
  };
  for (const std::vector<dataset::StampedPose>* poses : others) take(*poses);
  // Padding, and a minimum extent on the short side so that a straight run is not a sliver.
  double span = std::max({view.width(), view.height(), 0.2});
  const double pad = 0.04 * span;
  view.x0 -= pad;
  view.x1 += pad;
  view.y0 -= pad;
  view.y1 += pad;
  span = std::max(view.width(), view.height());
  const double min_side = 0.3 * span;
  if (view.width() < min_side) {
    const double c = 0.5 * (view.x0 + view.x1);
    view.x0 = c - 0.5 * min_side;
    view.x1 = c + 0.5 * min_side;
  }
  if (view.height() < min_side) {
    const double c = 0.5 * (view.y0 + view.y1);
    view.y0 = c - 0.5 * min_side;
    view.y1 = c + 0.5 * min_side;
  }
  const double step = nice_step(span, 8);
  view.x0 = std::floor(view.x0 / step - 1e-9) * step;
  view.y0 = std::floor(view.y0 / step - 1e-9) * step;
  view.x1 = std::ceil(view.x1 / step + 1e-9) * step;
  view.y1 = std::ceil(view.y1 / step + 1e-9) * step;
  return TrajectoryView{view.x0, view.y0, view.x1, view.y1, step, outside};
}

}  // namespace harmoloc::sim_host
