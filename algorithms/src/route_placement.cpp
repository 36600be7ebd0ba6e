#include "harmoloc/algorithms/route_placement.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Sparse>

namespace harmoloc::algorithms {

void ticks_at(const std::vector<OdometrySample>& odo, double t, double& left, double& right) {
  if (t <= odo.front().t_s) {
    left = static_cast<double>(odo.front().left_ticks);
    right = static_cast<double>(odo.front().right_ticks);
    return;
  }
  if (t >= odo.back().t_s) {
    left = static_cast<double>(odo.back().left_ticks);
    right = static_cast<double>(odo.back().right_ticks);
    return;
  }
  const auto it = std::upper_bound(odo.begin(), odo.end(), t,
                                   [](double v, const OdometrySample& s) { return v < s.t_s; });
  const OdometrySample& b = *it;
  const OdometrySample& a = *(it - 1);
  const double span = b.t_s - a.t_s;
  const double u = span > 0.0 ? (t - a.t_s) / span : 0.0;
  left = static_cast<double>(a.left_ticks) + u * static_cast<double>(b.left_ticks - a.left_ticks);
  right =
      static_cast<double>(a.right_ticks) + u * static_cast<double>(b.right_ticks - a.right_ticks);
}

namespace {

struct Node {
  double t_s;
  double left, right;  // cumulative ticks, interpolated
};

double angle_near(double angle, double reference) {
  return reference + wrap_angle_rad(angle - reference);
}

// Rotation that turns the dead-reckoned chord (a -> b) into the labels' chord, or false when
// either chord is too short to have a direction.
bool chord_rotation(const Pose2& dr_a, const Pose2& dr_b, const PlacementLabel& la,
                    const PlacementLabel& lb, double& phi) {
  constexpr double kMinChord_m = 0.02;
  const double dx = dr_b.x_m - dr_a.x_m, dy = dr_b.y_m - dr_a.y_m;
  const double lx = lb.x_m - la.x_m, ly = lb.y_m - la.y_m;
  if (std::hypot(dx, dy) < kMinChord_m || std::hypot(lx, ly) < kMinChord_m) return false;
  phi = std::atan2(ly, lx) - std::atan2(dy, dx);
  return true;
}

}  // namespace

std::vector<OdometrySample> unwrap_counters(const std::vector<double>& t_s,
                                            const std::vector<std::uint32_t>& left,
                                            const std::vector<std::uint32_t>& right,
                                            std::uint8_t counter_bits) {
  std::vector<OdometrySample> out;
  out.reserve(t_s.size());
  std::int64_t l = 0, r = 0;
  for (std::size_t i = 0; i < t_s.size(); ++i) {
    if (i > 0) {
      l += wrapped_delta(left[i - 1], left[i], counter_bits);
      r += wrapped_delta(right[i - 1], right[i], counter_bits);
    }
    out.push_back(OdometrySample{t_s[i], l, r});
  }
  return out;
}

PlacementResult place_by_odometry(const std::vector<double>& query_t_s,
                                  const std::vector<OdometrySample>& odometry,
                                  const DiffDriveGeometry& geometry,
                                  const std::vector<PlacementLabel>& labels,
                                  const PlacementOptions& opt) {
  if (odometry.size() < 2) throw std::invalid_argument("no wheel odometry over the run");
  if (labels.size() < 2) throw std::invalid_argument("at least 2 labels are needed");
  for (std::size_t l = 1; l < labels.size(); ++l) {
    if (!(labels[l].t_s > labels[l - 1].t_s))
      throw std::invalid_argument("label times must increase");
  }
  for (std::size_t q = 1; q < query_t_s.size(); ++q) {
    if (query_t_s[q] < query_t_s[q - 1]) throw std::invalid_argument("query times must increase");
  }

  // Nodes: every query and every label time, merged.
  constexpr double kSameTime_s = 1e-7;
  std::vector<double> times = query_t_s;
  for (const PlacementLabel& l : labels) times.push_back(l.t_s);
  std::sort(times.begin(), times.end());
  std::vector<double> unique_times;
  for (double t : times) {
    if (unique_times.empty() || t - unique_times.back() > kSameTime_s) unique_times.push_back(t);
  }
  const auto node_of = [&](double t) {
    const auto it = std::lower_bound(unique_times.begin(), unique_times.end(), t - kSameTime_s);
    return static_cast<std::size_t>(it - unique_times.begin());
  };
  const std::size_t n = unique_times.size();
  std::vector<Node> nodes(n);
  for (std::size_t k = 0; k < n; ++k) {
    nodes[k].t_s = unique_times[k];
    ticks_at(odometry, unique_times[k], nodes[k].left, nodes[k].right);
  }
  std::vector<std::size_t> label_node(labels.size());
  for (std::size_t l = 0; l < labels.size(); ++l) label_node[l] = node_of(labels[l].t_s);

  // Odometry between consecutive nodes: the arc's displacement in the first node's frame.
  const double left_m_per_tick = left_metres_per_tick(geometry);
  const double right_m_per_tick = right_metres_per_tick(geometry);
  struct Step {
    double u, v, w, distance;
  };
  std::vector<Step> steps(n > 0 ? n - 1 : 0);
  std::vector<double> travel(n, 0.0);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double lm = (nodes[k + 1].left - nodes[k].left) * left_m_per_tick;
    const double rm = (nodes[k + 1].right - nodes[k].right) * right_m_per_tick;
    const OdometryDelta d{0.5 * (lm + rm), (rm - lm) / geometry.track_m};
    const Pose2 rel = apply_arc(Pose2{}, d);
    steps[k] = Step{rel.x_m, rel.y_m, d.yaw_rad, d.distance_m};
    travel[k + 1] = travel[k] + std::fabs(d.distance_m);
  }

  // Dead reckoning from the origin, heading unwrapped.
  std::vector<Pose2> dr(n);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double c = std::cos(dr[k].yaw_rad), s = std::sin(dr[k].yaw_rad);
    dr[k + 1].x_m = dr[k].x_m + c * steps[k].u - s * steps[k].v;
    dr[k + 1].y_m = dr[k].y_m + s * steps[k].u + c * steps[k].v;
    dr[k + 1].yaw_rad = dr[k].yaw_rad + steps[k].w;
  }

  // A global rotation (least squares over all labels) for segments without a usable chord.
  double global_phi = 0.0;
  {
    double mx = 0, my = 0, ax = 0, ay = 0;
    for (std::size_t l = 0; l < labels.size(); ++l) {
      mx += labels[l].x_m;
      my += labels[l].y_m;
      ax += dr[label_node[l]].x_m;
      ay += dr[label_node[l]].y_m;
    }
    const double inv = 1.0 / static_cast<double>(labels.size());
    mx *= inv, my *= inv, ax *= inv, ay *= inv;
    double sxx = 0, sxy = 0;
    for (std::size_t l = 0; l < labels.size(); ++l) {
      const double px = dr[label_node[l]].x_m - ax, py = dr[label_node[l]].y_m - ay;
      const double qx = labels[l].x_m - mx, qy = labels[l].y_m - my;
      sxx += px * qx + py * qy;
      sxy += px * qy - py * qx;
    }
    global_phi = std::atan2(sxy, sxx);
  }

  // Initial trajectory: each stretch between two labels is the dead reckoning turned so that
  // its chord matches the labels', started on the first label, with what is left at the second
  // label spread along the stretch by travel (a bridge).
  std::vector<Pose2> pose(n);
  std::vector<double> phi_of_segment(labels.size() + 1, global_phi);
  {
    double phi = global_phi;
    bool have = false;
    for (std::size_t l = 0; l + 1 < labels.size(); ++l) {
      double p = 0.0;
      if (chord_rotation(dr[label_node[l]], dr[label_node[l + 1]], labels[l], labels[l + 1], p)) {
        phi = have ? angle_near(p, phi) : p;
        have = true;
      }
      phi_of_segment[l + 1] = phi;
    }
    // Segments before the first usable chord take the first one found.
    std::size_t first = 1;
    while (first < labels.size() && phi_of_segment[first] == global_phi) ++first;
    if (first < labels.size()) {
      for (std::size_t s = 1; s < first; ++s) phi_of_segment[s] = phi_of_segment[first];
    }
    phi_of_segment[0] = phi_of_segment[1];
    phi_of_segment[labels.size()] = phi_of_segment[labels.size() - 1];
  }
  const auto place_from = [&](std::size_t anchor_label, double phi, std::size_t k) {
    const Pose2& a = dr[label_node[anchor_label]];
    const double c = std::cos(phi), s = std::sin(phi);
    const double dx = dr[k].x_m - a.x_m, dy = dr[k].y_m - a.y_m;
    return Pose2{labels[anchor_label].x_m + c * dx - s * dy,
                 labels[anchor_label].y_m + s * dx + c * dy, dr[k].yaw_rad + phi};
  };
  for (std::size_t k = 0; k < n; ++k) {
    const auto it = std::upper_bound(label_node.begin(), label_node.end(), k);
    const auto after = static_cast<std::size_t>(it - label_node.begin());  // labels at nodes <= k
    if (after == 0) {
      pose[k] = place_from(0, phi_of_segment[0], k);
    } else if (after >= labels.size()) {
      pose[k] = place_from(labels.size() - 1, phi_of_segment[labels.size()], k);
    } else {
      const std::size_t a = after - 1, b = after;
      const double phi = phi_of_segment[b];
      Pose2 p = place_from(a, phi, k);
      const Pose2 end = place_from(a, phi, label_node[b]);
      const double span = travel[label_node[b]] - travel[label_node[a]];
      const double tspan = nodes[label_node[b]].t_s - nodes[label_node[a]].t_s;
      const double u = span > 1e-9 ? (travel[k] - travel[label_node[a]]) / span
                                   : (nodes[k].t_s - nodes[label_node[a]].t_s) / tspan;
      p.x_m += u * (labels[b].x_m - end.x_m);
      p.y_m += u * (labels[b].y_m - end.y_m);
      pose[k] = p;
    }
  }
  // Headings continuous along the chain.
  for (std::size_t k = 1; k < n; ++k)
    pose[k].yaw_rad = angle_near(pose[k].yaw_rad, pose[k - 1].yaw_rad + steps[k - 1].w);

  // Leave-one-out check of each label: predicted from the odometry between its neighbours.
  PlacementResult result;
  result.label_residual_m.assign(labels.size(), -1.0);
  for (std::size_t l = 1; l + 1 < labels.size(); ++l) {
    const std::size_t a = l - 1, b = l + 1;
    double phi = 0.0;
    if (!chord_rotation(dr[label_node[a]], dr[label_node[b]], labels[a], labels[b], phi))
      phi = phi_of_segment[l];
    Pose2 p = place_from(a, phi, label_node[l]);
    const Pose2 end = place_from(a, phi, label_node[b]);
    const double span = travel[label_node[b]] - travel[label_node[a]];
    const double tspan = nodes[label_node[b]].t_s - nodes[label_node[a]].t_s;
    const double u = span > 1e-9 ? (travel[label_node[l]] - travel[label_node[a]]) / span
                                 : (nodes[label_node[l]].t_s - nodes[label_node[a]].t_s) / tspan;
    p.x_m += u * (labels[b].x_m - end.x_m);
    p.y_m += u * (labels[b].y_m - end.y_m);
    result.label_residual_m[l] = std::hypot(p.x_m - labels[l].x_m, p.y_m - labels[l].y_m);
  }

  // Gauss-Newton over the chain: odometry steps and labels.
  const auto dim = static_cast<Eigen::Index>(3 * n);
  Eigen::VectorXd state(dim);
  for (std::size_t k = 0; k < n; ++k) {
    state(static_cast<Eigen::Index>(3 * k)) = pose[k].x_m;
    state(static_cast<Eigen::Index>(3 * k + 1)) = pose[k].y_m;
    state(static_cast<Eigen::Index>(3 * k + 2)) = pose[k].yaw_rad;
  }
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  bool analysed = false;
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(n * 36 + labels.size() * 3);
  for (int iteration = 0; iteration < opt.iterations; ++iteration) {
    triplets.clear();
    Eigen::VectorXd gradient = Eigen::VectorXd::Zero(dim);
    const auto add = [&](std::size_t i, std::size_t j, double v) {
      triplets.emplace_back(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j), v);
    };
    for (std::size_t k = 0; k + 1 < n; ++k) {
      const std::size_t i = 3 * k, j = 3 * (k + 1);
      const double th = state(static_cast<Eigen::Index>(i + 2));
      const double c = std::cos(th), s = std::sin(th);
      const double dx = state(static_cast<Eigen::Index>(j)) - state(static_cast<Eigen::Index>(i));
      const double dy =
          state(static_cast<Eigen::Index>(j + 1)) - state(static_cast<Eigen::Index>(i + 1));
      const Step& st = steps[k];
      const double r[3] = {
          c * dx + s * dy - st.u, -s * dx + c * dy - st.v,
          state(static_cast<Eigen::Index>(j + 2)) - state(static_cast<Eigen::Index>(i + 2)) - st.w};
      const double along = std::max(opt.step_floor_m, opt.travel_noise * std::fabs(st.distance));
      const double turn =
          std::max(opt.turn_floor_rad,
                   opt.turn_noise * (std::fabs(st.w) + std::fabs(st.distance) / geometry.track_m));
      const double wgt[3] = {1.0 / (along * along), 1.0 / (along * along), 1.0 / (turn * turn)};
      // Jacobian rows over (x_k, y_k, th_k, x_k+1, y_k+1, th_k+1).
      const double jac[3][6] = {{-c, -s, -s * dx + c * dy, c, s, 0.0},
                                {s, -c, -c * dx - s * dy, -s, c, 0.0},
                                {0.0, 0.0, -1.0, 0.0, 0.0, 1.0}};
      const std::size_t index[6] = {i, i + 1, i + 2, j, j + 1, j + 2};
      // The whole 6 x 6 block every time (zeros included): the factorisation's pattern is
      // analysed once and must not change between iterations.
      for (int a = 0; a < 6; ++a) {
        double g = 0.0;
        for (int row = 0; row < 3; ++row) g += jac[row][a] * wgt[row] * r[row];
        gradient(static_cast<Eigen::Index>(index[a])) += g;
        for (int b = 0; b < 6; ++b) {
          double hab = 0.0;
          for (int row = 0; row < 3; ++row) hab += jac[row][a] * wgt[row] * jac[row][b];
          add(index[a], index[b], hab);
        }
      }
    }
    const double wl = 1.0 / (opt.label_sigma_m * opt.label_sigma_m);
    const double wy = 1.0 / (opt.label_yaw_sigma_rad * opt.label_yaw_sigma_rad);
    for (std::size_t l = 0; l < labels.size(); ++l) {
      const std::size_t i = 3 * label_node[l];
      gradient(static_cast<Eigen::Index>(i)) +=
          wl * (state(static_cast<Eigen::Index>(i)) - labels[l].x_m);
      gradient(static_cast<Eigen::Index>(i + 1)) +=
          wl * (state(static_cast<Eigen::Index>(i + 1)) - labels[l].y_m);
      add(i, i, wl);
      add(i + 1, i + 1, wl);
      if (labels[l].has_yaw) {
        gradient(static_cast<Eigen::Index>(i + 2)) +=
            wy * wrap_angle_rad(state(static_cast<Eigen::Index>(i + 2)) - labels[l].yaw_rad);
        add(i + 2, i + 2, wy);
      }
    }
    // A tiny pull towards the current state keeps the system definite where nothing pins a
    // node (it does not move the solution).
    for (Eigen::Index i = 0; i < dim; ++i)
      add(static_cast<std::size_t>(i), static_cast<std::size_t>(i), 1e-6);
    Eigen::SparseMatrix<double> h(dim, dim);
    h.setFromTriplets(triplets.begin(), triplets.end());
    if (!analysed) {
      solver.analyzePattern(h);
      analysed = true;
    }
    solver.factorize(h);
    if (solver.info() != Eigen::Success) throw std::runtime_error("placement: the solve failed");
    const Eigen::VectorXd delta = solver.solve(-gradient);
    if (!delta.allFinite()) throw std::runtime_error("placement: the solve diverged");
    state += delta;
    result.gauss_newton_iterations = iteration + 1;
    if (delta.cwiseAbs().maxCoeff() < 1e-7) break;
  }

  result.label_fit_m.resize(labels.size());
  for (std::size_t l = 0; l < labels.size(); ++l) {
    const auto i = static_cast<Eigen::Index>(3 * label_node[l]);
    result.label_fit_m[l] = std::hypot(state(i) - labels[l].x_m, state(i + 1) - labels[l].y_m);
  }
  result.poses.reserve(query_t_s.size());
  result.travel_m.reserve(query_t_s.size());
  result.support_m.reserve(query_t_s.size());
  std::vector<double> label_travel(labels.size());
  for (std::size_t l = 0; l < labels.size(); ++l) label_travel[l] = travel[label_node[l]];
  for (double t : query_t_s) {
    const std::size_t k = node_of(t);
    const auto i = static_cast<Eigen::Index>(3 * k);
    result.poses.push_back(Pose2{state(i), state(i + 1), wrap_angle_rad(state(i + 2))});
    result.travel_m.push_back(travel[k]);
    const auto it = std::lower_bound(label_travel.begin(), label_travel.end(), travel[k]);
    double support = 1e300;
    if (it != label_travel.end()) support = std::min(support, *it - travel[k]);
    if (it != label_travel.begin()) support = std::min(support, travel[k] - *(it - 1));
    result.support_m.push_back(support);
  }
  return result;
}

}  // namespace harmoloc::algorithms
