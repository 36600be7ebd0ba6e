#include "harmoloc/sim_host/scene_geometry_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "board_sighting_residuals.hpp"
#include "robust_least_squares.hpp"

namespace harmoloc::sim_host {

namespace {

// Field of view (deg), k1, k2, principal offset x and y (px), pitch (deg), forward offset (m).
constexpr int kCameraParams = 7;
using CameraParams = Eigen::Matrix<double, kCameraParams, 1>;
using detail::kBoardParams;
constexpr double kBoardStep = 1e-4;  // metres, log size, radians
constexpr std::array<double, kCameraParams> kCameraSteps = {1e-3, 1e-5, 1e-5, 1e-3,
                                                            1e-3, 1e-3, 1e-5};

CameraParams params_of(const CameraSpec& c) {
  CameraParams p;
  p << c.horizontal_fov_deg, c.k1, c.k2, c.principal_offset_x_px, c.principal_offset_y_px,
      c.pitch_deg, c.forward_offset_m;
  return p;
}

template <typename P>
CameraSpec camera_of(const P& p, const CameraSpec& like) {
  CameraSpec c = like;
  c.horizontal_fov_deg = p[0];
  c.k1 = p[1];
  c.k2 = p[2];
  c.principal_offset_x_px = p[3];
  c.principal_offset_y_px = p[4];
  c.pitch_deg = p[5];
  c.forward_offset_m = p[6];
  return c;
}

}  // namespace

SceneGeometryFit fit_scene_geometry(const CameraSpec& camera_start,
                                    const std::vector<std::vector<BoardSighting>>& sightings,
                                    const std::vector<BoardSpec>& board_starts,
                                    const SceneFitOptions& options) {
  SceneGeometryFit fit;
  fit.camera = camera_start;
  const std::size_t count = std::min(sightings.size(), board_starts.size());
  fit.boards.resize(count);
  for (std::size_t b = 0; b < count; ++b) fit.boards[b].board = board_starts[b];

  // The boards seen from enough places, and their sightings.
  std::vector<std::size_t> in;
  std::vector<std::vector<BoardSighting>> used;
  std::vector<Eigen::Index> rows_at{0};
  for (std::size_t b = 0; b < count; ++b) {
    std::vector<BoardSighting> u = usable_sightings(sightings[b], options.board);
    if (u.size() < options.board.min_sightings) continue;
    in.push_back(b);
    rows_at.push_back(rows_at.back() + static_cast<Eigen::Index>(3 * u.size()));
    used.push_back(std::move(u));
  }
  if (in.size() < 2) return fit;

  // 1. Each board alone under the rough camera, its scales widened 8 times so that the camera's
  // error does not make every sighting an outlier; facings tried all round.
  BoardFitOptions wide = options.board;
  wide.sqrt_area_scale *= 8.0;
  wide.centroid_scale_px *= 8.0;
  std::vector<BoardSpec> starts;
  {
    const LensModel lens(camera_start);
    for (std::size_t b : in) {
      starts.push_back(
          options.from_fit
              ? board_starts[b]
              : fit_board_geometry(camera_start, lens, sightings[b], board_starts[b], wide).board);
    }
  }

  // 2. The camera and all those boards at once, the scales narrowed 8, 4, 2, 1 times.
  const Eigen::Index n = kCameraParams + kBoardParams * static_cast<Eigen::Index>(in.size());
  Eigen::VectorXd p(n);
  p.head(kCameraParams) = params_of(camera_start);
  for (std::size_t k = 0; k < in.size(); ++k) {
    p.segment(kCameraParams + kBoardParams * static_cast<Eigen::Index>(k), kBoardParams) =
        detail::board_params(starts[k]);
  }
  std::vector<double> steps(kCameraSteps.begin(), kCameraSteps.end());
  BoardFitOptions o = options.board;
  const auto board_k = [&](const Eigen::VectorXd& q, std::size_t k) {
    return detail::board_from_params(
        q.data() + kCameraParams + kBoardParams * static_cast<Eigen::Index>(k), starts[k]);
  };
  // The boards' aspect residuals after all the sightings' (one a board).
  const Eigen::Index aspect_rows =
      detail::has_aspect_residual(options.board) ? static_cast<Eigen::Index>(in.size()) : 0;
  auto residuals = [&](const Eigen::VectorXd& q, Eigen::VectorXd& r) {
    r.resize(rows_at.back() + aspect_rows);
    // A field of view outside (1, 179) degrees has no pinhole: every residual as large as any.
    if (!(q[0] > 1.0 && q[0] < 179.0)) {
      r.setConstant(1e6);
      return;
    }
    const CameraSpec camera = camera_of(q.head(kCameraParams), camera_start);
    const LensModel lens(camera);
    for (std::size_t k = 0; k < in.size(); ++k) {
      detail::board_residuals(camera, lens, board_k(q, k), used[k], o, r, rows_at[k]);
    }
    for (Eigen::Index k = 0; k < aspect_rows; ++k) {
      r[rows_at.back() + k] =
          detail::aspect_residual(q.data() + kCameraParams + kBoardParams * k, o);
    }
  };
  // A board's parameters move only its own rows: those columns cost one board's sightings each.
  const auto jacobian = [&](const Eigen::VectorXd& q, Eigen::Index rows, Eigen::MatrixXd& jac) {
    jac.setZero(rows, n);
    Eigen::VectorXd rp, rm;
    for (Eigen::Index j = 0; j < kCameraParams; ++j) {
      Eigen::VectorXd a = q, b = q;
      a[j] += kCameraSteps[static_cast<std::size_t>(j)];
      b[j] -= kCameraSteps[static_cast<std::size_t>(j)];
      residuals(a, rp);
      residuals(b, rm);
      jac.col(j) = (rp - rm) / (2.0 * kCameraSteps[static_cast<std::size_t>(j)]);
    }
    const CameraSpec camera = camera_of(q.head(kCameraParams), camera_start);
    const LensModel lens(camera);
    for (std::size_t k = 0; k < in.size(); ++k) {
      const Eigen::Index first = kCameraParams + kBoardParams * static_cast<Eigen::Index>(k);
      const Eigen::Index block = rows_at[k + 1] - rows_at[k];
      for (Eigen::Index j = 0; j < kBoardParams; ++j) {
        Eigen::VectorXd a = q, b = q;
        a[first + j] += kBoardStep;
        b[first + j] -= kBoardStep;
        detail::board_residuals(camera, lens, board_k(a, k), used[k], o, rp);
        detail::board_residuals(camera, lens, board_k(b, k), used[k], o, rm);
        jac.block(rows_at[k], first + j, block, 1) = (rp - rm) / (2.0 * kBoardStep);
      }
      if (aspect_rows > 0) {
        const Eigen::Index row = rows_at.back() + static_cast<Eigen::Index>(k);
        jac(row, first + 3) = 1.0 / o.aspect_log_scale;
        jac(row, first + 4) = -1.0 / o.aspect_log_scale;
      }
    }
  };
  for (const double widen : {8.0, 4.0, 2.0, 1.0}) {
    if (options.from_fit && widen > 1.0) continue;
    o.sqrt_area_scale = options.board.sqrt_area_scale * widen;
    o.centroid_scale_px = options.board.centroid_scale_px * widen;
    // The wide runs only bring the fit near: a few steps each.
    const int iterations = widen > 1.0 ? options.max_iterations / 4 : options.max_iterations;
    const detail::RobustSolution sol =
        detail::robust_least_squares(residuals, jacobian, p, o.huber, iterations);
    p = sol.p;
    ++fit.rounds;
  }
  fit.camera = camera_of(p.head(kCameraParams), camera_start);

  // 3. Each board once more under the fitted camera, from its joint fit: its own figures.
  const LensModel lens(fit.camera);
  BoardFitOptions final_options = options.board;
  final_options.other_facings = false;
  detail::ResidualSpread spread;
  std::size_t fitted = 0;
  for (std::size_t k = 0; k < in.size(); ++k) {
    BoardFit& bf = fit.boards[in[k]];
    bf = fit_board_geometry(fit.camera, lens, sightings[in[k]], board_k(p, k), final_options);
    if (!bf.ok) continue;
    ++fitted;
    Eigen::VectorXd r;
    detail::board_residuals(fit.camera, lens, bf.board, used[k], options.board, r);
    spread.add(r, options.board.huber);
  }
  fit.rms_sqrt_area = spread.rms(0, options.board.sqrt_area_scale);
  fit.rms_column_px = spread.rms(1, options.board.centroid_scale_px);
  fit.rms_row_px = spread.rms(2, options.board.centroid_scale_px);
  fit.ok = fitted >= 2;
  return fit;
}

}  // namespace harmoloc::sim_host
