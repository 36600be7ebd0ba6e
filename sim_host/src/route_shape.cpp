#include "harmoloc/sim_host/route.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "route_parts.hpp"

namespace harmoloc::sim_host {

namespace route_detail {

// Catmull-Rom through the waypoints, densely sampled (@p steps points a segment): end points
// repeated, or closed (back to the first waypoint, neighbours taken round the loop).
Polyline make_path(const std::vector<std::array<double, 2>>& w, bool closed, int steps) {
  if (w.size() < 2) throw std::runtime_error("a route needs at least 2 waypoints");
  if (closed && w.size() < 3) throw std::runtime_error("a loop needs at least 3 waypoints");
  Polyline p;
  p.closed = closed;
  const std::size_t n = w.size();
  const auto count = static_cast<std::ptrdiff_t>(n);
  auto pt = [&](std::ptrdiff_t i) {
    if (closed) return w[static_cast<std::size_t>(((i % count) + count) % count)];
    return w[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(i, 0, count - 1))];
  };
  const int kSteps = steps;
  const std::size_t segments = closed ? n : n - 1;
  for (std::size_t i = 0; i < segments; ++i) {
    const auto p0 = pt(static_cast<std::ptrdiff_t>(i) - 1), p1 = pt(static_cast<std::ptrdiff_t>(i)),
               p2 = pt(static_cast<std::ptrdiff_t>(i) + 1),
               p3 = pt(static_cast<std::ptrdiff_t>(i) + 2);
    for (int k = (i == 0 ? 0 : 1); k <= kSteps; ++k) {
      const double t = static_cast<double>(k) / kSteps, t2 = t * t, t3 = t2 * t;
      double c[2];
      for (int d = 0; d < 2; ++d) {
        c[d] = 0.5 * (2 * p1[d] + (-p0[d] + p2[d]) * t +
                      (2 * p0[d] - 5 * p1[d] + 4 * p2[d] - p3[d]) * t2 +
                      (-p0[d] + 3 * p1[d] - 3 * p2[d] + p3[d]) * t3);
      }
      p.x.push_back(c[0]);
      p.y.push_back(c[1]);
    }
  }
  p.measure();
  return p;
}

// Distance covered after time t on a leg of length L with a trapezoidal speed profile.
double leg_distance(double t, double length, double v, double a, double& duration) {
  double t_acc = v / a;
  double d_acc = 0.5 * a * t_acc * t_acc;
  if (2.0 * d_acc > length) {  // triangle: never reaches cruise speed
    t_acc = std::sqrt(length / a);
    d_acc = 0.5 * length;
    v = a * t_acc;
  }
  const double t_cruise = (length - 2.0 * d_acc) / v;
  duration = 2.0 * t_acc + t_cruise;
  if (t <= 0.0) return 0.0;
  if (t < t_acc) return 0.5 * a * t * t;
  if (t < t_acc + t_cruise) return d_acc + v * (t - t_acc);
  if (t < duration) {
    const double r = duration - t;
    return length - 0.5 * a * r * r;
  }
  return length;
}

}  // namespace route_detail

using namespace route_detail;

namespace {

// The route's curve: a tour's straight legs, or the smooth curve through the waypoints.
Polyline route_path(const RouteSpec& route) {
  if (route.shape != RouteShape::kTour)
    return make_path(route.waypoints_m, route.shape == RouteShape::kLoop);
  if (route.waypoints_m.size() < 2) throw std::runtime_error("a tour needs at least 2 waypoints");
  Polyline p;
  for (const auto& w : route.waypoints_m) {
    p.x.push_back(w[0]);
    p.y.push_back(w[1]);
  }
  p.measure();
  return p;
}

}  // namespace

std::vector<std::array<double, 2>> route_curve(const RouteSpec& route, double step_m) {
  const Polyline path = route_path(route);
  const double length = path.length();
  const auto n = std::max<std::size_t>(2, static_cast<std::size_t>(std::ceil(length / step_m)) + 1);
  std::vector<std::array<double, 2>> out;
  out.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    double x, y, tx, ty;
    path.at(length * static_cast<double>(i) / static_cast<double>(n - 1), x, y, tx, ty);
    out.push_back({x, y});
  }
  return out;
}

double route_length_m(const RouteSpec& route) {
  return route_path(route).length();
}

bool route_crosses_itself(const RouteSpec& route, std::string* why) {
  if (route.shape == RouteShape::kTour) return false;  // a tour may cross itself
  constexpr double kClearance_m = 0.05;
  const bool loop = route.shape == RouteShape::kLoop;
  const Polyline path = make_path(route.waypoints_m, loop, 40);
  const std::size_t n = path.x.size();
  const double length = path.length();
  // Two points closer than the clearance whose distance along the curve is more than a few times
  // it (so not neighbours), or segments that intersect.
  const auto along = [&](std::size_t i, std::size_t j) {
    const double d = std::fabs(path.s[i] - path.s[j]);
    return loop ? std::min(d, length - d) : d;
  };
  const auto cross = [](double ax, double ay, double bx, double by, double cx, double cy, double dx,
                        double dy) {
    const auto orient = [](double px, double py, double qx, double qy, double rx, double ry) {
      return (qx - px) * (ry - py) - (qy - py) * (rx - px);
    };
    const double o1 = orient(ax, ay, bx, by, cx, cy), o2 = orient(ax, ay, bx, by, dx, dy);
    const double o3 = orient(cx, cy, dx, dy, ax, ay), o4 = orient(cx, cy, dx, dy, bx, by);
    return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0));
  };
  for (std::size_t i = 0; i + 1 < n; ++i) {
    for (std::size_t j = i + 2; j + 1 < n; ++j) {
      if (along(i, j) < 4.0 * kClearance_m || along(i + 1, j) < 4.0 * kClearance_m ||
          along(i, j + 1) < 4.0 * kClearance_m)
        continue;
      const bool close = std::hypot(path.x[i] - path.x[j], path.y[i] - path.y[j]) < kClearance_m;
      if (close || cross(path.x[i], path.y[i], path.x[i + 1], path.y[i + 1], path.x[j], path.y[j],
                         path.x[j + 1], path.y[j + 1])) {
        if (why != nullptr) {
          std::ostringstream m;
          m << "the " << (loop ? "loop" : "route") << " crosses or touches itself near ("
            << path.x[i] << ", " << path.y[i] << ")";
          *why = m.str();
        }
        return true;
      }
    }
  }
  return false;
}

}  // namespace harmoloc::sim_host
