#include "harmoloc/sim_host/forward_map_training.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "forward_map_training_parts.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/map_codec.hpp"

namespace harmoloc::sim_host::forward_map_training_detail {

namespace {

// Frames within 25 degrees of the nearest one's heading count as the same way along the route.
const double kSamePassCos = std::cos(25.0 * algorithms::kPi / 180.0);

// Whether @p p is of the same pass as a frame at (@p t_s, @p travel_m), for validation.
bool same_pass(const Positioned& p, double t_s, double travel_m, double exclude_s,
               double exclude_m) {
  if (travel_m >= 0.0 && p.travel_m >= 0.0) return std::fabs(p.travel_m - travel_m) < exclude_m;
  return std::fabs(p.t_s - t_s) < exclude_s;
}

// The frames in square buckets, for the nearest frame and the frames within a radius of a
// place without a pass over every frame (a map of 40000 cells over a run of 4000 frames).
class FrameIndex {
 public:
  FrameIndex(const std::vector<Positioned>& frames, double bucket_m)
      : frames_(frames), bucket_m_(bucket_m) {
    x0_ = y0_ = std::numeric_limits<double>::infinity();
    double x1 = -x0_, y1 = -y0_;
    for (const Positioned& p : frames) {
      x0_ = std::min(x0_, p.x_m);
      y0_ = std::min(y0_, p.y_m);
      x1 = std::max(x1, p.x_m);
      y1 = std::max(y1, p.y_m);
    }
    columns_ = static_cast<long>(std::floor((x1 - x0_) / bucket_m_)) + 1;
    rows_ = static_cast<long>(std::floor((y1 - y0_) / bucket_m_)) + 1;
    first_.assign(static_cast<std::size_t>(columns_ * rows_) + 1U, 0);
    std::vector<std::size_t> bucket_of(frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      bucket_of[i] = bucket(column(frames[i].x_m), row(frames[i].y_m));
      ++first_[bucket_of[i] + 1U];
    }
    for (std::size_t b = 1; b < first_.size(); ++b) first_[b] += first_[b - 1];
    order_.resize(frames.size());
    std::vector<std::size_t> fill(first_.begin(), first_.end() - 1);
    for (std::size_t i = 0; i < frames.size(); ++i) order_[fill[bucket_of[i]]++] = i;
  }

  /// Squared distance from (x, y) to the nearest frame @p keep accepts (infinity: none); that
  /// frame in @p which when given (nullptr: none).
  template <typename Keep>
  double nearest_d2(double x, double y, Keep keep, const Positioned** which = nullptr) const {
    const long c0 = column(x), r0 = row(y);
    const long reach = std::max({c0, columns_ - 1 - c0, r0, rows_ - 1 - r0});
    double best = std::numeric_limits<double>::infinity();
    if (which != nullptr) *which = nullptr;
    for (long ring = 0; ring <= reach; ++ring) {
      // Every frame not yet seen lies at least (ring - 1) buckets away.
      const double near = std::max(0.0, static_cast<double>(ring - 1)) * bucket_m_;
      if (near * near > best) break;
      for (long r = r0 - ring; r <= r0 + ring; ++r) {
        if (r < 0 || r >= rows_) continue;
        const bool edge = r == r0 - ring || r == r0 + ring;
        for (long c = c0 - ring; c <= c0 + ring; c += edge ? 1 : 2 * ring) {
          if (c >= 0 && c < columns_) {
            const std::size_t b = bucket(c, r);
            for (std::size_t k = first_[b]; k < first_[b + 1]; ++k) {
              const Positioned& p = frames_[order_[k]];
              if (!keep(p)) continue;
              const double d2 = (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y);
              if (d2 < best) {
                best = d2;
                if (which != nullptr) *which = &p;
              }
            }
          }
          if (ring == 0) break;
        }
      }
    }
    return best;
  }

  /// Calls @p f for every frame within @p radius_m of (x, y) (and perhaps a few beyond).
  template <typename F>
  void within(double x, double y, double radius_m, F f) const {
    const long c0 = std::max(0L, column(x - radius_m)),
               c1 = std::min(columns_ - 1, column(x + radius_m));
    const long r0 = std::max(0L, row(y - radius_m)), r1 = std::min(rows_ - 1, row(y + radius_m));
    for (long r = r0; r <= r1; ++r) {
      for (long c = c0; c <= c1; ++c) {
        const std::size_t b = bucket(c, r);
        for (std::size_t k = first_[b]; k < first_[b + 1]; ++k) f(frames_[order_[k]]);
      }
    }
  }

 private:
  long column(double x) const {
    const double u = std::floor((x - x0_) / bucket_m_);
    return static_cast<long>(std::clamp(u, -1.0e6, 1.0e6));
  }
  long row(double y) const {
    const double u = std::floor((y - y0_) / bucket_m_);
    return static_cast<long>(std::clamp(u, -1.0e6, 1.0e6));
  }
  std::size_t bucket(long c, long r) const {
    return static_cast<std::size_t>(std::clamp(r, 0L, rows_ - 1) * columns_ +
                                    std::clamp(c, 0L, columns_ - 1));
  }

  const std::vector<Positioned>& frames_;
  double bucket_m_;
  double x0_, y0_;
  long columns_ = 1, rows_ = 1;
  std::vector<std::size_t> first_;  // frames of bucket b: order_[first_[b] .. first_[b + 1])
  std::vector<std::size_t> order_;
};

// Kernel-weighted mean of the frames' features at (x, y); weights relative to the nearest
// frame, so that a place far from every frame takes its nearest frames' values. Frames of the
// same pass as (@p t_s, @p travel_m) are left out when an exclusion is given (validation
// against other passes). Returns false when no frame is left.
bool kernel_mean(const FrameIndex& index, double x, double y, double bandwidth_m,
                 std::size_t boards, double t_s, double travel_m, double exclude_s,
                 double exclude_m, double* out) {
  const bool exclude = exclude_s > 0.0 || exclude_m > 0.0;
  const auto keep = [&](const Positioned& p) {
    return !exclude || !same_pass(p, t_s, travel_m, exclude_s, exclude_m);
  };
  const double d2_min = index.nearest_d2(x, y, keep);
  if (!std::isfinite(d2_min)) return false;
  // Weights below e^-30 of the nearest frame's do not count.
  constexpr double kCut = 30.0;
  const double inv = 0.5 / (bandwidth_m * bandwidth_m);
  double sum_w = 0.0;
  for (std::size_t b = 0; b < boards; ++b) out[b] = 0.0;
  index.within(x, y, std::sqrt(d2_min + kCut / inv), [&](const Positioned& p) {
    if (!keep(p)) return;
    const double e = ((p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y) - d2_min) * inv;
    if (e > kCut) return;
    const double w = std::exp(-e);
    sum_w += w;
    for (std::size_t b = 0; b < boards; ++b) out[b] += w * static_cast<double>((*p.features)[b]);
  });
  for (std::size_t b = 0; b < boards; ++b) out[b] /= sum_w;
  return true;
}

// The kernel-weighted sums of kernel_mean at (x, y), and with @p with_heading each frame's heading
// as (cos, sin): what the mean and the first harmonic over the heading (heading_fit) are fitted
// from.
struct KernelSums {
  double w = 0.0, c = 0.0, s = 0.0, cc = 0.0, cs = 0.0, ss = 0.0;
  std::array<double, kMaxBoards> a{}, ca{}, sa{};
};

bool kernel_sums(const FrameIndex& index, double x, double y, double bandwidth_m,
                 std::size_t boards, double t_s, double travel_m, double exclude_s,
                 double exclude_m, bool with_heading, KernelSums& out) {
  const bool exclude = exclude_s > 0.0 || exclude_m > 0.0;
  const auto keep = [&](const Positioned& p) {
    return !exclude || !same_pass(p, t_s, travel_m, exclude_s, exclude_m);
  };
  out = KernelSums{};
  const double d2_min = index.nearest_d2(x, y, keep);
  if (!std::isfinite(d2_min)) return false;
  constexpr double kCut = 30.0;
  const double inv = 0.5 / (bandwidth_m * bandwidth_m);
  index.within(x, y, std::sqrt(d2_min + kCut / inv), [&](const Positioned& p) {
    if (!keep(p)) return;
    const double e = ((p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y) - d2_min) * inv;
    if (e > kCut) return;
    const double w = std::exp(-e);
    out.w += w;
    if (!with_heading) {
      for (std::size_t b = 0; b < boards; ++b)
        out.a[b] += w * static_cast<double>((*p.features)[b]);
      return;
    }
    const double c = std::cos(p.yaw_rad), s = std::sin(p.yaw_rad);
    out.c += w * c;
    out.s += w * s;
    out.cc += w * c * c;
    out.cs += w * c * s;
    out.ss += w * s * s;
    for (std::size_t b = 0; b < boards; ++b) {
      const double a = static_cast<double>((*p.features)[b]);
      out.a[b] += w * a;
      out.ca[b] += w * c * a;
      out.sa[b] += w * s * a;
    }
  });
  return out.w > 0.0;
}

// The first harmonic over the heading fitted to @p k: per board, a0 + c cos(yaw) + s sin(yaw),
// by least squares with a ridge of @p ridge times the weight on (c, s), so that it falls back to
// the weighted mean (c = s = 0) where the frames' headings do not spread (a route). A ridge of
// infinity (or not finite): the mean.
struct HeadingFit {
  std::array<double, kMaxBoards> a0{}, c{}, s{};
  double predict(std::size_t b, double cos_yaw, double sin_yaw) const {
    return std::max(0.0, a0[b] + c[b] * cos_yaw + s[b] * sin_yaw);
  }
};

HeadingFit heading_fit(const KernelSums& k, std::size_t boards, double ridge) {
  HeadingFit f;
  const double mc = k.c / k.w, ms = k.s / k.w;
  // The centred second moments, plus the ridge.
  const bool terms = std::isfinite(ridge);
  const double a11 = k.cc - k.w * mc * mc + (terms ? ridge * k.w : 0.0);
  const double a12 = k.cs - k.w * mc * ms;
  const double a22 = k.ss - k.w * ms * ms + (terms ? ridge * k.w : 0.0);
  const double det = a11 * a22 - a12 * a12;
  for (std::size_t b = 0; b < boards; ++b) {
    const double mean = k.a[b] / k.w;
    if (terms && det > 0.0) {
      const double r1 = k.ca[b] - mc * k.a[b], r2 = k.sa[b] - ms * k.a[b];
      f.c[b] = (a22 * r1 - a12 * r2) / det;
      f.s[b] = (a11 * r2 - a12 * r1) / det;
    }
    f.a0[b] = mean - f.c[b] * mc - f.s[b] * ms;
  }
  return f;
}

// Every frame's heading and bearings as unit vectors, computed once (the sums below visit each
// frame many times).
struct FrameVectors {
  const Positioned* first = nullptr;
  std::vector<double> heading;  // cos, sin per frame
  std::vector<double> bearing;  // cos, sin per frame and board; NaN where none
  std::size_t boards = 0;

  FrameVectors(const std::vector<Positioned>& frames, std::size_t board_count)
      : first(frames.data()),
        heading(2 * frames.size()),
        bearing(2 * frames.size() * board_count, std::numeric_limits<double>::quiet_NaN()),
        boards(board_count) {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Positioned& p = frames[i];
      heading[2 * i] = std::cos(p.yaw_rad);
      heading[2 * i + 1] = std::sin(p.yaw_rad);
      if (p.bearing_rad == nullptr) continue;
      for (std::size_t b = 0; b < boards; ++b) {
        const double v = static_cast<double>(p.bearing_rad[b]);
        if (!std::isfinite(v)) continue;
        bearing[2 * (i * boards + b)] = std::cos(v);
        bearing[2 * (i * boards + b) + 1] = std::sin(v);
      }
    }
  }
  std::size_t of(const Positioned& p) const { return static_cast<std::size_t>(&p - first); }
};

// The heading terms from a wide kernel, local-linear in the place: per board
// a0 + gx dx + gy dy + c cos(yaw) + s sin(yaw) around (x, y), dx and dy in kernel widths. A
// floor driven in lanes sees a place at the headings of the lanes through it only; its other
// headings were driven on the neighbouring lanes, a lane spacing away (a floor driven forth and
// back: every other lane), which a kernel of a few centimetres never reaches. The wide kernel
// reaches them and the slopes take out how the areas change over that distance, so that the
// harmonic is the heading's share alone.
struct WideSums {
  double w = 0.0;
  std::array<std::array<double, 5>, 5> m{};           // the normal matrix's upper triangle
  std::array<std::array<double, 5>, kMaxBoards> r{};  // per board: sum w phi o
};

// Weights below e^-9 of the nearest frame's do not count (the kernel is wide: a longer cut
// would take in the whole floor at every place).
constexpr double kWideCut = 9.0;

// @p v: the frames' headings as unit vectors (of the frames the index holds).
bool wide_sums(const FrameIndex& index, const FrameVectors& v, double x, double y,
               double bandwidth_m, std::size_t boards, double t_s, double travel_m,
               double exclude_s, double exclude_m, WideSums& out) {
  const bool exclude = exclude_s > 0.0 || exclude_m > 0.0;
  const auto keep = [&](const Positioned& p) {
    return p.has_yaw && (!exclude || !same_pass(p, t_s, travel_m, exclude_s, exclude_m));
  };
  out = WideSums{};
  const double d2_min = index.nearest_d2(x, y, keep);
  if (!std::isfinite(d2_min)) return false;
  const double inv = 0.5 / (bandwidth_m * bandwidth_m);
  index.within(x, y, std::sqrt(d2_min + kWideCut / inv), [&](const Positioned& p) {
    if (!keep(p)) return;
    const double dx = p.x_m - x, dy = p.y_m - y;
    const double e = (dx * dx + dy * dy - d2_min) * inv;
    if (e > kWideCut) return;
    const double w = std::exp(-e);
    const std::size_t at = v.of(p);
    const double phi[5] = {1.0, dx / bandwidth_m, dy / bandwidth_m, v.heading[2 * at],
                           v.heading[2 * at + 1]};
    out.w += w;
    for (int i = 0; i < 5; ++i)
      for (int j = i; j < 5; ++j) out.m[i][j] += w * phi[i] * phi[j];
    for (std::size_t b = 0; b < boards; ++b) {
      const double wo = w * static_cast<double>((*p.features)[b]);
      for (int i = 0; i < 5; ++i) out.r[b][i] += wo * phi[i];
    }
  });
  return out.w > 0.0;
}

// Solves @p k's least squares with a ridge of @p ridge times the weight on (c, s) (infinite:
// none fitted) and a small one on the slopes (so that a place seen along one line only keeps a
// level across it). The fit's a0, c and s are the cell's (its slopes are zero at its centre).
// False when singular.
bool wide_fit(const WideSums& k, std::size_t boards, double ridge, HeadingFit& f) {
  constexpr double kSlopeRidge = 1e-3;
  double a[5][5];
  for (int i = 0; i < 5; ++i)
    for (int j = i; j < 5; ++j) a[i][j] = a[j][i] = k.m[i][j];
  a[1][1] += kSlopeRidge * k.w;
  a[2][2] += kSlopeRidge * k.w;
  // An infinite ridge: no harmonic (a finite one this large leaves it below rounding).
  const double r = std::isfinite(ridge) ? ridge : 1e12;
  a[3][3] += r * k.w;
  a[4][4] += r * k.w;
  // Cholesky, in place in the lower triangle.
  for (int j = 0; j < 5; ++j) {
    double d = a[j][j];
    for (int p = 0; p < j; ++p) d -= a[j][p] * a[j][p];
    if (!(d > 1e-12 * k.w)) return false;
    a[j][j] = std::sqrt(d);
    for (int i = j + 1; i < 5; ++i) {
      double v = a[i][j];
      for (int p = 0; p < j; ++p) v -= a[i][p] * a[j][p];
      a[i][j] = v / a[j][j];
    }
  }
  f = HeadingFit{};
  for (std::size_t b = 0; b < boards; ++b) {
    double z[5];
    for (int i = 0; i < 5; ++i) {
      double v = k.r[b][i];
      for (int p = 0; p < i; ++p) v -= a[i][p] * z[p];
      z[i] = v / a[i][i];
    }
    for (int i = 4; i >= 0; --i) {
      double v = z[i];
      for (int p = i + 1; p < 5; ++p) v -= a[p][i] * z[p];
      z[i] = v / a[i][i];
    }
    f.a0[b] = z[0];
    f.c[b] = z[3];
    f.s[b] = z[4];
  }
  return true;
}

// The wide fit's harmonic with the level of the narrow kernel's sums @p k (kernel_sums with
// headings): a0 is the narrow mean of the areas less the harmonic, so the place keeps the
// narrow kernel's sharpness and takes the other headings' change from the wide one.
HeadingFit with_narrow_level(const HeadingFit& wide, const KernelSums& k, std::size_t boards) {
  HeadingFit f = wide;
  for (std::size_t b = 0; b < boards; ++b)
    f.a0[b] = (k.a[b] - wide.c[b] * k.c - wide.s[b] * k.s) / k.w;
  return f;
}

// Board bearings around a place: per board, the kernel-weighted sums of the unit vectors of the
// world bearings of the frames that saw it whole, and the kernel weight of all frames.
struct BearingSums {
  std::array<double, kMaxBoards> sin{}, cos{}, weight{};
  // The same frames' weighted features (each over its angle_gain) and angular half-widths, and
  // the squares of their image angles (visibility).
  std::array<double, kMaxBoards> feature{}, half_width{}, angle_sq{};
  double all = 0.0;
};

// A frame's view of a board carried from where it stood to a nearby place (x, y) by where the
// board stands: its feature scales with the inverse square of the distance (within 4 times
// either way), its angular half-width with the inverse distance, and its bearing turns by the
// change of the board's direction. Between the lanes of a coverage run the nearest frames stand
// 10-20 cm away: a board 2 m off shows 10-20% more or less area there.
struct Carry {
  double area = 1.0, width = 1.0, cos = 1.0, sin = 0.0;
};

Carry carry(const double* places, std::size_t b, double from_x, double from_y, double x, double y) {
  Carry c;
  if (places == nullptr || std::isnan(places[2 * b])) return c;
  const double fx = places[2 * b] - from_x, fy = places[2 * b + 1] - from_y;
  const double tx = places[2 * b] - x, ty = places[2 * b + 1] - y;
  const double f2 = fx * fx + fy * fy, t2 = tx * tx + ty * ty;
  if (!(f2 > 1e-4 && t2 > 1e-4)) return c;
  c.area = std::clamp(f2 / t2, 0.25, 4.0);
  c.width = std::sqrt(c.area);
  const double inv = 1.0 / std::sqrt(f2 * t2);
  c.cos = (fx * tx + fy * ty) * inv;
  c.sin = (fx * ty - fy * tx) * inv;
  return c;
}

// Over the frames within @p reach_m of (x, y) that run within 25 degrees of the heading whose
// unit vector is (@p anchor_cos, @p anchor_sin) (every frame when @p every_heading) and that
// @p keep accepts, weighted exp(-(d^2 - d2_min) / 2h^2); with @p places (where the boards stand,
// x and y per board, NaN: not placed), each frame's view carried to (x, y); each frame's feature
// taken back to the axis by @p angle_gain (ForwardMap::visibility_angle_gain) centred on
// @p axis_rad (ForwardMap::visibility_axis_rad).
template <typename Keep>
BearingSums bearing_sums(const FrameIndex& index, const FrameVectors& v, double x, double y,
                         double anchor_cos, double anchor_sin, bool every_heading, double d2_min,
                         double reach_m, double h, Keep keep, const double* places = nullptr,
                         float angle_gain = 0.0F, float axis_rad = 0.0F) {
  BearingSums s;
  const double inv = 0.5 / (h * h);
  index.within(x, y, reach_m, [&](const Positioned& p) {
    if (!p.has_yaw || p.bearing_rad == nullptr || !keep(p)) return;
    const std::size_t i = v.of(p);
    if (!every_heading &&
        v.heading[2 * i] * anchor_cos + v.heading[2 * i + 1] * anchor_sin < kSamePassCos)
      return;
    const double d = (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y);
    const double e = (d - d2_min) * inv;
    if (e > 30.0) return;  // below e^-30 of the nearest frame's weight
    const double w = std::exp(-e);
    s.all += w;
    const double* unit = v.bearing.data() + 2 * i * v.boards;
    for (std::size_t b = 0; b < v.boards; ++b) {
      if (std::isnan(unit[2 * b])) continue;
      const Carry c = carry(places, b, p.x_m, p.y_m, x, y);
      s.cos[b] += w * (unit[2 * b] * c.cos - unit[2 * b + 1] * c.sin);
      s.sin[b] += w * (unit[2 * b + 1] * c.cos + unit[2 * b] * c.sin);
      s.weight[b] += w;
      // From the optical axis, where the gain is centred.
      const auto angle = static_cast<float>(algorithms::wrap_angle_rad(
                             p.yaw_rad - static_cast<double>(p.bearing_rad[b]))) -
                         axis_rad;
      s.angle_sq[b] += w * static_cast<double>(angle * angle);
      s.feature[b] += w * c.area * static_cast<double>((*p.features)[b]) /
                      static_cast<double>(algorithms::angle_gain(angle_gain, angle));
      if (p.half_width_rad != nullptr)
        s.half_width[b] += w * c.width * static_cast<double>(p.half_width_rad[b]);
    }
  });
  return s;
}

// The mean bearing of board b from @p s when most of the frames' weight saw it and their
// bearings agree (the resultant of the unit vectors at least 0.95 of the weight, i.e. a spread
// within about 18 degrees); false otherwise. With @p every_heading (bearings seen from the
// camera's place, frames of every heading) a frame facing away from the board says nothing
// against it: the board needs only some weight near the place, e^-2 of the nearest frame's (a
// frame within two kernel widths of as near as the nearest).
bool mean_bearing(const BearingSums& s, std::size_t b, bool every_heading, double& out) {
  if (!(s.weight[b] > 0.0)) return false;
  if (every_heading ? s.weight[b] < std::exp(-2.0) : s.weight[b] < 0.5 * s.all) return false;
  const double resultant = std::hypot(s.sin[b], s.cos[b]);
  if (resultant < 0.95 * s.weight[b]) return false;
  out = std::atan2(s.sin[b], s.cos[b]);
  return true;
}

// Fills @p out's bearings: each board's spread between passes (frames predicted from the other
// passes running the same way, as the areas' noise is measured: a robust spread, 1.4826 times
// the median absolute residual, at least 0.1 degree; a board needs 20 such residuals), then
// every stored cell's bearings with the same kernel.
// @p every_heading: @p frames are placed at the camera's place, and the bearings there are taken
// from frames of every heading (fit_bearings below).
void fit_bearings_from(const std::vector<Positioned>& frames, const std::vector<char>& comparable,
                       const FrameIndex& index, const FrameVectors& vectors, bool every_heading,
                       std::size_t boards, const ForwardMapOptions& opt, const double* law,
                       const double* places, double x0, double y0, double cell, ForwardMap& out,
                       ForwardMapReport& report) {
  const double h = report.bandwidth_m;
  constexpr double kCut = 30.0;  // weights below e^-30 of the nearest frame's do not count
  std::vector<std::vector<double>> residuals(boards);
  const double near_m = std::max(2.0 * report.pass_spread_m, 0.01);
  // Visibility needs the bearings seen from the camera's place (there a board's whole feature
  // holds at every heading) and takes the heading terms' storage.
  const bool floor = report.pass_heading_spread_rad >=
                     static_cast<double>(algorithms::kFloorMapPassHeadingSpread_rad);
  report.visibility_wanted = opt.visibility || (opt.visibility_on_floors && floor);
  const bool visibility = every_heading && report.visibility_wanted &&
                          ForwardMap::kHeadingTermStorage && !out.has_heading_terms;
  const auto half_fov = static_cast<float>(std::fabs(0.5 * law[0] + 0.125 * law[1]));
  const auto axis = static_cast<float>(law[2]);
  // Per board, the squared residuals of the areas as the visibility predicts them from other
  // passes, and how many frames it could not predict (no bearing from other passes there).
  std::vector<double> seen_sq(boards, 0.0);
  std::vector<std::size_t> seen_n(boards, 0), unseen_n(boards, 0);
  // With visibility, the frames' views are carried to the place by where the boards stand.
  const double* carried = visibility ? places : nullptr;
  // Each comparable frame with the sums of the other passes near it (taken back to the axis by
  // @p gain), for @p visit(i, sums).
  const auto over_frames = [&](float gain, auto visit) {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Positioned& p = frames[i];
      if (!comparable[i] || p.bearing_rad == nullptr) continue;
      const double* heading = vectors.heading.data();
      const auto other = [&](const Positioned& q) {
        const std::size_t k = vectors.of(q);
        return q.has_yaw && q.bearing_rad != nullptr &&
               (every_heading ||
                heading[2 * k] * heading[2 * i] + heading[2 * k + 1] * heading[2 * i + 1] >=
                    kSamePassCos) &&
               !same_pass(q, p.t_s, p.travel_m, opt.exclude_same_pass_s, opt.exclude_same_pass_m);
      };
      // The nearest such frame, looked for only as far as another pass counts as near (the
      // comparable bound): a search over the whole run for each frame would take minutes.
      double d2_min = std::numeric_limits<double>::infinity();
      index.within(p.x_m, p.y_m, near_m, [&](const Positioned& q) {
        if (other(q))
          d2_min = std::min(d2_min,
                            (q.x_m - p.x_m) * (q.x_m - p.x_m) + (q.y_m - p.y_m) * (q.y_m - p.y_m));
      });
      if (!(d2_min <= near_m * near_m)) continue;
      visit(i, bearing_sums(index, vectors, p.x_m, p.y_m, vectors.heading[2 * i],
                            vectors.heading[2 * i + 1], every_heading, d2_min,
                            std::sqrt(d2_min + 2.0 * kCut * h * h), h, other, carried, gain, axis));
    }
  };
  // The angle gain: a board seen whole shows more (or less) towards the frame's edge than its
  // neighbours' views at other angles predict; the least-squares slope of the log of the ratio
  // over the difference of the squared angles, over every board.
  float gain = 0.0F;
  if (visibility) {
    double xy = 0.0, xx = 0.0;
    std::size_t n = 0;
    over_frames(0.0F, [&](std::size_t i, const BearingSums& s) {
      const Positioned& p = frames[i];
      for (std::size_t b = 0; b < boards; ++b) {
        double mean = 0.0;
        const double v = static_cast<double>((*p.features)[b]);
        if (!std::isfinite(static_cast<double>(p.bearing_rad[b])) || !(v > 0.0) ||
            !mean_bearing(s, b, every_heading, mean) || !(s.feature[b] > 0.0))
          continue;
        const double a =
            algorithms::wrap_angle_rad(p.yaw_rad - static_cast<double>(p.bearing_rad[b])) -
            static_cast<double>(axis);
        const double x = a * a - s.angle_sq[b] / s.weight[b];
        xy += x * std::log(v * s.weight[b] / s.feature[b]);
        xx += x * x;
        ++n;
      }
    });
    if (n >= 50 && xx > 0.0) gain = static_cast<float>(std::clamp(xy / xx, -2.0, 2.0));
  }
  over_frames(gain, [&](std::size_t i, const BearingSums& s) {
    const Positioned& p = frames[i];
    for (std::size_t b = 0; b < boards; ++b) {
      double mean = 0.0;
      const bool known = mean_bearing(s, b, every_heading, mean);
      if (visibility) {
        if (known) {
          const auto a = static_cast<float>(algorithms::wrap_angle_rad(p.yaw_rad - mean));
          const double predicted =
              s.feature[b] / s.weight[b] *
              static_cast<double>(
                  algorithms::angle_gain(gain, a - axis) *
                  algorithms::visible_share(
                      half_fov, static_cast<float>(s.half_width[b] / s.weight[b]), std::fabs(a)));
          const double r = static_cast<double>((*p.features)[b]) - predicted;
          seen_sq[b] += r * r;
          ++seen_n[b];
        } else {
          ++unseen_n[b];
        }
      }
      const double v = static_cast<double>(p.bearing_rad[b]);
      if (!std::isfinite(v) || !known) continue;
      residuals[b].push_back(std::fabs(algorithms::wrap_angle_rad(v - mean)));
    }
  });
  report.bearing_sigma_rad.assign(boards, 0.0);
  bool any = false;
  for (std::size_t b = 0; b < boards; ++b) {
    std::vector<double>& r = residuals[b];
    report.bearing_residuals += r.size();
    if (r.size() < 20 || !(out.sigma[b] > 0.0F)) continue;
    auto mid = r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2);
    std::nth_element(r.begin(), mid, r.end());
    // At most 1 rad (the map format's bound): a board whose bearings spread that far tells
    // nothing, and is left to its area.
    const double spread = std::max(1.4826 * *mid, 0.1 * algorithms::kPi / 180.0);
    if (spread > 1.0) continue;
    report.bearing_sigma_rad[b] = spread;
    out.bearing_sigma_rad[b] = static_cast<float>(report.bearing_sigma_rad[b]);
    any = true;
  }
  if (!any) return;
  out.has_bearings = true;
  out.bearing_a1_rad = static_cast<float>(law[0]);
  out.bearing_a3_rad = static_cast<float>(law[1]);
  report.has_bearings = true;
  out.has_visibility = visibility;
  out.visibility_angle_gain = visibility ? gain : 0.0F;
  // Within half the half field of view (the map format's bound is the whole): an axis beyond
  // that is no lens's.
  out.visibility_axis_rad = visibility ? std::clamp(axis, -0.5F * half_fov, 0.5F * half_fov) : 0.0F;
  report.visibility = visibility;
  report.visibility_angle_gain = visibility ? static_cast<double>(gain) : 0.0;
  // With visibility each board's noise is that of the areas it predicts from other passes, and
  // the old noise where it predicts none (those places keep the cell's expected feature).
  for (std::size_t b = 0; visibility && b < boards; ++b) {
    const std::size_t n = seen_n[b] + unseen_n[b];
    if (!(out.sigma[b] > 0.0F) || seen_n[b] < 20 || n == 0) continue;
    const double old = static_cast<double>(out.sigma[b]);
    const double ms =
        (seen_sq[b] + static_cast<double>(unseen_n[b]) * old * old) / static_cast<double>(n);
    report.sigma[b] = std::max(std::sqrt(ms), std::max(1e-2 * old, 1e-4));
    out.sigma[b] = static_cast<float>(report.sigma[b]);
  }
  const auto with_yaw = [](const Positioned& p) { return p.has_yaw && p.bearing_rad != nullptr; };
  const auto every = [](const Positioned&) { return true; };
  for (std::uint32_t r = 0; r < out.rows; ++r) {
    for (std::uint32_t c = 0; c < out.columns; ++c) {
      const std::size_t at = out.index(c, r);
      if (at == ForwardMap::kVoidCell) continue;
      const double x = x0 + c * cell, y = y0 + r * cell;
      // The direction of the nearest frame, as for the cell's heading: where a route crosses
      // itself or is driven both ways, the camera (ahead of the axle) sees the boards from
      // elsewhere on the other pass.
      std::size_t anchor = 0;
      double d2_min = std::numeric_limits<double>::infinity();
      const double reach = std::sqrt(index.nearest_d2(x, y, with_yaw)) + 1e-6;
      if (!std::isfinite(reach)) continue;
      index.within(x, y, reach, [&](const Positioned& p) {
        const double d = (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y);
        if (with_yaw(p) && d < d2_min) {
          d2_min = d;
          anchor = vectors.of(p);
        }
      });
      if (!std::isfinite(d2_min)) continue;
      const BearingSums s = bearing_sums(
          index, vectors, x, y, vectors.heading[2 * anchor], vectors.heading[2 * anchor + 1],
          every_heading, d2_min, std::sqrt(d2_min + 2.0 * kCut * h * h), h, every, carried, gain);
      bool stored = false;
      for (std::size_t b = 0; b < boards; ++b) {
        double mean = 0.0;
        if (!(out.bearing_sigma_rad[b] > 0.0F) || !mean_bearing(s, b, every_heading, mean))
          continue;
        out.bearing_rad[at * kMaxBoards + b] = static_cast<float>(mean);
        if (visibility) {
          float* t = out.heading_terms.data() + (at * kMaxBoards + b) * 2;
          t[0] = static_cast<float>(s.feature[b] / s.weight[b]);
          t[1] = static_cast<float>(s.half_width[b] / s.weight[b]);
        }
        stored = true;
      }
      report.bearing_cells += stored ? 1U : 0U;
    }
  }
}

// Fills @p out's bearings (fit_bearings_from). Seen from the axle's place, a board's world
// bearing changes with the heading (the camera is ahead of the axle), so a cell takes it only
// from the frames running the way its nearest frame does: on a floor driven at several headings
// about half of the places the robot faces a board from have none. Given the camera's offset
// (opt.camera_forward_m), every frame is put at its camera's place, where the bearing depends on
// the place alone, and a cell takes the bearings of every heading.
void fit_bearings(const std::vector<Positioned>& frames, const std::vector<char>& comparable,
                  const FrameIndex& index, const FrameVectors& vectors, std::size_t boards,
                  const ForwardMapOptions& opt, const double* law, const double* places, double x0,
                  double y0, double cell, ForwardMap& out, ForwardMapReport& report) {
  const double d = opt.camera_forward_m;
  if (!(std::isfinite(d) && d != 0.0)) {
    fit_bearings_from(frames, comparable, index, vectors, false, boards, opt, law, places, x0, y0,
                      cell, out, report);
    return;
  }
  std::vector<Positioned> seen(frames);
  for (std::size_t i = 0; i < seen.size(); ++i) {
    if (!seen[i].has_yaw) continue;
    seen[i].x_m += d * vectors.heading[2 * i];
    seen[i].y_m += d * vectors.heading[2 * i + 1];
  }
  const FrameIndex seen_index(seen, 0.05);
  // The same headings and bearings, frame for frame: only where the frames stand moved.
  FrameVectors seen_vectors = vectors;
  seen_vectors.first = seen.data();
  fit_bearings_from(seen, comparable, seen_index, seen_vectors, true, boards, opt, law, places, x0,
                    y0, cell, out, report);
  if (out.has_bearings) {
    out.bearing_camera_forward_m = static_cast<float>(d);
    report.bearing_camera_forward_m = d;
  }
}

// Divides @p sq's per-board sums of squares over @p n frames by n and returns their mean over
// the modelled boards (0 when none is).
double mean_over_modelled(std::vector<double>& sq, std::size_t n,
                          const std::vector<bool>& modelled) {
  double total = 0.0;
  std::size_t used = 0;
  for (std::size_t b = 0; b < sq.size(); ++b) {
    sq[b] /= static_cast<double>(n);
    if (modelled[b]) {
      total += sq[b];
      ++used;
    }
  }
  return used > 0 ? total / static_cast<double>(used) : 0.0;
}

}  // namespace

ForwardMapReport fit_grid(std::vector<Positioned>& frames, std::size_t board_count,
                          const ForwardMapOptions& opt, algorithms::ForwardMap& out,
                          ForwardMapReport report, const double* law, const double* board_places) {
  if (frames.size() < 8) {
    throw std::runtime_error("forward map: only " + std::to_string(frames.size()) +
                             " frames could be positioned (at least 8 needed)");
  }

  // Which boards change at all: a board never seen (or always the same) is not modelled.
  std::vector<bool> modelled(board_count, false);
  for (std::size_t b = 0; b < board_count; ++b) {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    for (const Positioned& p : frames) {
      lo = std::min(lo, (*p.features)[b]);
      hi = std::max(hi, (*p.features)[b]);
    }
    modelled[b] = hi > lo;
  }

  // Kernel width: the candidate whose prediction of each frame from other passes fits best.
  std::vector<double> mean(board_count);
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_sq;
  // Frames with another pass close by in position: within twice the median distance from a
  // frame to the nearest frame of another pass. Elsewhere (the turn at the end of a route driven
  // once each way) leaving the own pass out leaves nothing near, and the residual would measure
  // extrapolation, not the noise a new run over the same place shows.
  std::vector<char> comparable(frames.size(), 0);
  const FrameIndex index(frames, 0.05);
  const FrameVectors vectors(frames, board_count);
  {
    std::vector<double> nearest(frames.size(), std::numeric_limits<double>::infinity());
    // With it, how far that frame of another pass turned from this one's heading.
    std::vector<double> turned;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Positioned& p = frames[i];
      const Positioned* other = nullptr;
      nearest[i] = std::sqrt(index.nearest_d2(
          p.x_m, p.y_m,
          [&](const Positioned& q) {
            return !same_pass(q, p.t_s, p.travel_m, opt.exclude_same_pass_s,
                              opt.exclude_same_pass_m);
          },
          &other));
      if (p.has_yaw && other != nullptr && other->has_yaw)
        turned.push_back(std::fabs(algorithms::wrap_angle_rad(other->yaw_rad - p.yaw_rad)));
    }
    // The upper quartile: a floor driven at two headings has about half its frames' nearest
    // other pass at the other heading, which puts the median on the edge between the two.
    if (!turned.empty()) {
      auto q3 = turned.begin() + static_cast<std::ptrdiff_t>(3 * turned.size() / 4);
      std::nth_element(turned.begin(), q3, turned.end());
      report.pass_heading_spread_rad = *q3;
    }
    std::vector<double> finite;
    for (double d : nearest) {
      if (std::isfinite(d)) finite.push_back(d);
    }
    if (!finite.empty()) {
      auto mid = finite.begin() + static_cast<std::ptrdiff_t>(finite.size() / 2);
      std::nth_element(finite.begin(), mid, finite.end());
      report.pass_spread_m = *mid;
      const double bound = std::max(2.0 * *mid, 0.01);
      for (std::size_t i = 0; i < frames.size(); ++i) comparable[i] = nearest[i] <= bound ? 1 : 0;
    }
  }
  // With headings, the first harmonic over the heading is tried too, with each ridge of the
  // options (a floor's passes over one place run at several headings, and the boards' areas
  // change with the heading); it is kept only where it predicts other passes clearly better.
  const bool try_terms = report.has_heading && !opt.heading_ridges.empty();
  std::vector<double> ridges{std::numeric_limits<double>::infinity()};
  if (try_terms) ridges.insert(ridges.end(), opt.heading_ridges.begin(), opt.heading_ridges.end());
  double best_terms = std::numeric_limits<double>::infinity(), terms_h = 0.0, terms_ridge = 0.0;
  std::vector<double> terms_sq;
  for (double h : opt.bandwidths_m) {
    std::vector<std::vector<double>> sq(ridges.size(), std::vector<double>(board_count, 0.0));
    std::size_t n = 0;
    KernelSums k;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Positioned& p = frames[i];
      if (!comparable[i]) continue;
      if (!kernel_sums(index, p.x_m, p.y_m, h, board_count, p.t_s, p.travel_m,
                       opt.exclude_same_pass_s, opt.exclude_same_pass_m, try_terms, k)) {
        continue;
      }
      ++n;
      const double cos_yaw = std::cos(p.yaw_rad), sin_yaw = std::sin(p.yaw_rad);
      for (std::size_t b = 0; b < board_count; ++b) {
        const double res = static_cast<double>((*p.features)[b]) - k.a[b] / k.w;
        sq[0][b] += res * res;
      }
      for (std::size_t r = 1; r < ridges.size(); ++r) {
        const HeadingFit fit = heading_fit(k, board_count, ridges[r]);
        for (std::size_t b = 0; b < board_count; ++b) {
          const double res =
              static_cast<double>((*p.features)[b]) - fit.predict(b, cos_yaw, sin_yaw);
          sq[r][b] += res * res;
        }
      }
    }
    if (n == 0) continue;
    for (std::size_t r = 0; r < ridges.size(); ++r) {
      const double total = mean_over_modelled(sq[r], n, modelled);
      if (r == 0 && total < best) {
        best = total;
        report.bandwidth_m = h;
        best_sq = sq[r];
      } else if (r > 0 && total < best_terms) {
        best_terms = total;
        terms_h = h;
        terms_ridge = ridges[r];
        terms_sq = sq[r];
      }
    }
  }
  // The heading terms from a wide kernel (wide_fit), alone or with the narrow kernel's level,
  // validated on the same frames: a frame whose wide fit fails keeps the narrow mean. The same
  // fits without the harmonic (an infinite ridge) are validated too: the terms must beat them as
  // well, so that what they are kept for is the heading, not the wide fit's slopes over the
  // place (on a route those alone can predict a little better than the narrow mean).
  bool terms_wide = false, terms_narrow_level = false;
  double terms_wide_h = 0.0, best_flat = std::numeric_limits<double>::infinity();
  if (try_terms && !opt.heading_bandwidths_m.empty() && !best_sq.empty()) {
    const double h_narrow = report.bandwidth_m;
    // Per wide kernel: the ridges of the options, then the infinite one; each alone and on the
    // narrow level.
    std::vector<double> wide_ridges(ridges.begin() + 1, ridges.end());
    wide_ridges.push_back(std::numeric_limits<double>::infinity());
    const std::size_t nh = opt.heading_bandwidths_m.size(), nr = wide_ridges.size();
    std::vector<std::vector<double>> sq(nh * nr * 2, std::vector<double>(board_count, 0.0));
    std::size_t n = 0;
    KernelSums narrow;
    WideSums wide;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const Positioned& p = frames[i];
      if (!comparable[i]) continue;
      if (!kernel_sums(index, p.x_m, p.y_m, h_narrow, board_count, p.t_s, p.travel_m,
                       opt.exclude_same_pass_s, opt.exclude_same_pass_m, true, narrow)) {
        continue;
      }
      ++n;
      const double cos_yaw = std::cos(p.yaw_rad), sin_yaw = std::sin(p.yaw_rad);
      for (std::size_t hi = 0; hi < nh; ++hi) {
        const bool summed =
            wide_sums(index, vectors, p.x_m, p.y_m, opt.heading_bandwidths_m[hi], board_count,
                      p.t_s, p.travel_m, opt.exclude_same_pass_s, opt.exclude_same_pass_m, wide);
        for (std::size_t ri = 0; ri < nr; ++ri) {
          HeadingFit fit;
          const bool ok = summed && wide_fit(wide, board_count, wide_ridges[ri], fit);
          const HeadingFit level = ok ? with_narrow_level(fit, narrow, board_count) : fit;
          for (std::size_t b = 0; b < board_count; ++b) {
            const double o = static_cast<double>((*p.features)[b]);
            const double fallback = narrow.a[b] / narrow.w;
            const double r0 = o - (ok ? fit.predict(b, cos_yaw, sin_yaw) : fallback);
            const double r1 = o - (ok ? level.predict(b, cos_yaw, sin_yaw) : fallback);
            sq[(hi * nr + ri) * 2][b] += r0 * r0;
            sq[(hi * nr + ri) * 2 + 1][b] += r1 * r1;
          }
        }
      }
    }
    for (std::size_t k = 0; n > 0 && k < sq.size(); ++k) {
      const double total = mean_over_modelled(sq[k], n, modelled);
      const double ridge = wide_ridges[(k / 2) % nr];
      if (!std::isfinite(ridge)) {
        best_flat = std::min(best_flat, total);
      } else if (total < best_terms) {
        best_terms = total;
        terms_h = h_narrow;
        terms_wide = true;
        terms_narrow_level = (k % 2) == 1;
        terms_wide_h = opt.heading_bandwidths_m[k / 2 / nr];
        terms_ridge = ridge;
        terms_sq = sq[k];
      }
    }
  }
  report.heading_terms_validation_rmse = std::isfinite(best_terms) ? std::sqrt(best_terms) : 0.0;
  const bool use_terms =
      try_terms && !best_sq.empty() &&
      best_terms < (1.0 - opt.heading_terms_min_gain) * std::min(best, best_flat);
  const std::vector<double> blind_sq = best_sq;
  if (use_terms) {
    report.mean_validation_rmse = std::sqrt(best);
    best = best_terms;
    report.bandwidth_m = terms_h;
    report.heading_ridge = terms_ridge;
    report.heading_bandwidth_m = terms_wide ? terms_wide_h : 0.0;
    report.heading_narrow_level = terms_narrow_level;
    best_sq = terms_sq;
  }
  if (best_sq.empty()) {
    // A single pass: no other pass to validate against; the smallest width, noise from itself.
    report.bandwidth_m = opt.bandwidths_m.front();
    best_sq.assign(board_count, 0.0);
    for (const Positioned& p : frames) {
      kernel_mean(index, p.x_m, p.y_m, report.bandwidth_m, board_count, p.t_s, -1.0, 0.0, 0.0,
                  mean.data());
      for (std::size_t b = 0; b < board_count; ++b) {
        const double r = static_cast<double>((*p.features)[b]) - mean[b];
        best_sq[b] += r * r / static_cast<double>(frames.size());
      }
    }
    best = 0.0;
    for (std::size_t b = 0; b < board_count; ++b) best += best_sq[b];
    best /= static_cast<double>(board_count);
  }
  report.validation_rmse = std::sqrt(best);

  // The grid over the training positions, its tiles stored where a training position lies
  // within the margin: the finest cell that fits the capacity.
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const Positioned& p : frames) {
    x0 = std::min(x0, p.x_m);
    y0 = std::min(y0, p.y_m);
    x1 = std::max(x1, p.x_m);
    y1 = std::max(y1, p.y_m);
  }
  x0 -= opt.margin_m;
  y0 -= opt.margin_m;
  x1 += opt.margin_m;
  y1 += opt.margin_m;
  const std::size_t max_tiles =
      opt.max_tiles > 0 ? std::min(opt.max_tiles, ForwardMap::kMaxTiles) : ForwardMap::kMaxTiles;
  constexpr std::uint32_t kSide = ForwardMap::kTileSide;
  double cell = opt.min_cell_m;
  std::uint32_t columns = 0, rows = 0;
  std::vector<std::uint8_t> stored;
  for (;; cell *= 1.05) {
    const auto cells_along = [&](double extent) {
      return static_cast<std::size_t>(std::ceil(extent / cell)) + 1U;
    };
    const std::size_t nc = cells_along(x1 - x0), nr = cells_along(y1 - y0);
    if (nc > ForwardMap::kMaxDimension || nr > ForwardMap::kMaxDimension) continue;
    columns = static_cast<std::uint32_t>(nc);
    rows = static_cast<std::uint32_t>(nr);
    const std::uint32_t tc = algorithms::tiles_along(columns), tr = algorithms::tiles_along(rows);
    if (static_cast<std::size_t>(tc) * tr > ForwardMap::kMaxTileGrid) continue;
    // The cells a lookup within the margin of a frame reads (a bilinear lookup reads the next
    // cell too), and the tiles that hold them.
    stored.assign(static_cast<std::size_t>(tc) * tr, 0);
    std::size_t count = 0;
    for (const Positioned& p : frames) {
      const auto first = [&](double v, double origin) {
        return static_cast<long>(std::floor((v - opt.margin_m - origin) / cell));
      };
      const auto last = [&](double v, double origin) {
        return static_cast<long>(std::floor((v + opt.margin_m - origin) / cell)) + 1;
      };
      const long c_lo = std::max(0L, first(p.x_m, x0)) / kSide;
      const long c_hi = std::min(static_cast<long>(columns) - 1, last(p.x_m, x0)) / kSide;
      const long r_lo = std::max(0L, first(p.y_m, y0)) / kSide;
      const long r_hi = std::min(static_cast<long>(rows) - 1, last(p.y_m, y0)) / kSide;
      for (long r = r_lo; r <= r_hi; ++r) {
        for (long c = c_lo; c <= c_hi; ++c) {
          std::uint8_t& t = stored[static_cast<std::size_t>(r) * tc + static_cast<std::size_t>(c)];
          count += t == 0 ? 1 : 0;
          t = 1;
        }
      }
    }
    if (count <= max_tiles) break;
  }
  algorithms::reset_in_place(out);
  if (!algorithms::lay_out_grid(out, columns, rows, stored.data()))
    throw std::runtime_error("forward map: the grid does not fit (internal error)");
  out.origin_x_m = static_cast<float>(x0);
  out.origin_y_m = static_cast<float>(y0);
  out.cell_m = static_cast<float>(cell);
  out.board_count = static_cast<std::uint32_t>(board_count);
  report.cells = out.stored_cells();
  report.sigma.assign(board_count, 0.0);
  report.heading_blind_sigma.assign(board_count, 0.0);
  for (std::size_t b = 0; b < board_count; ++b) {
    if (!modelled[b]) continue;
    // A floor: a board whose frames agree perfectly must still not make the filter certain.
    double peak = 0.0;
    for (const Positioned& p : frames) peak = std::max(peak, static_cast<double>((*p.features)[b]));
    report.sigma[b] = std::max(std::sqrt(best_sq[b]), std::max(1e-3 * peak, 1e-4));
    out.sigma[b] = static_cast<float>(report.sigma[b]);
    report.heading_blind_sigma[b] =
        blind_sq.empty() ? report.sigma[b]
                         : std::max(std::sqrt(blind_sq[b]), std::max(1e-3 * peak, 1e-4));
  }
  out.has_heading = report.has_heading;
  out.has_heading_terms = use_terms;
  // Heading coverage: each frame's sectors (those whose centre lies within the reach of its
  // heading), or-ed over the frames the kernel weighs at a cell.
  const bool cover = report.has_heading && ForwardMap::kHeadingTermStorage;
  out.has_heading_coverage = cover;
  std::vector<std::uint16_t> frame_sectors(cover ? frames.size() : 0U, 0);
  for (std::size_t i = 0; i < frame_sectors.size(); ++i) {
    if (!frames[i].has_yaw) continue;
    for (int k = 0; k < ForwardMap::kHeadingSectors; ++k) {
      const double centre =
          -algorithms::kPi + (k + 0.5) * static_cast<double>(ForwardMap::kHeadingSector_rad);
      if (std::fabs(algorithms::wrap_angle_rad(centre - frames[i].yaw_rad)) <=
          static_cast<double>(ForwardMap::kHeadingReach_rad))
        frame_sectors[i] |= static_cast<std::uint16_t>(1U << k);
    }
  }
  std::size_t known_cells = 0, known_sectors = 0;
  const auto any = [](const Positioned&) { return true; };
  for (std::uint32_t r = 0; r < out.rows; ++r) {
    for (std::uint32_t c = 0; c < out.columns; ++c) {
      const std::size_t at = out.index(c, r);
      if (at == ForwardMap::kVoidCell) continue;
      const double x = x0 + c * cell, y = y0 + r * cell;
      float* e = out.expected.data() + at * algorithms::kMaxBoards;
      if (use_terms) {
        KernelSums k;
        kernel_sums(index, x, y, report.bandwidth_m, board_count, 0.0, -1.0, 0.0, 0.0, true, k);
        HeadingFit fit = heading_fit(k, board_count, report.heading_ridge);
        WideSums wide;
        HeadingFit wide_result;
        if (report.heading_bandwidth_m > 0.0 &&
            wide_sums(index, vectors, x, y, report.heading_bandwidth_m, board_count, 0.0, -1.0, 0.0,
                      0.0, wide) &&
            wide_fit(wide, board_count, report.heading_ridge, wide_result)) {
          fit = report.heading_narrow_level ? with_narrow_level(wide_result, k, board_count)
                                            : wide_result;
        }
        float* t = out.heading_terms.data() + at * algorithms::kMaxBoards * 2;
        for (std::size_t b = 0; b < board_count; ++b) {
          if (!modelled[b]) continue;
          e[b] = static_cast<float>(fit.a0[b]);
          t[2 * b] = static_cast<float>(fit.c[b]);
          t[2 * b + 1] = static_cast<float>(fit.s[b]);
        }
      } else {
        kernel_mean(index, x, y, report.bandwidth_m, board_count, 0.0, -1.0, 0.0, 0.0, mean.data());
        for (std::size_t b = 0; b < board_count; ++b)
          e[b] = modelled[b] ? static_cast<float>(mean[b]) : 0.0F;
      }
      const double d2 = index.nearest_d2(x, y, any);
      out.route_distance_m[at] = static_cast<float>(std::sqrt(d2));
      // The heading of the frames near the cell that run the way the nearest one does: their
      // circular mean, kernel-weighted, so one frame's wobble is not the cell's heading, and
      // where a route crosses itself the other pass is left out rather than averaged in.
      if (report.has_heading) {
        const auto with_yaw = [](const Positioned& p) { return p.has_yaw; };
        const double yaw_reach = std::sqrt(index.nearest_d2(x, y, with_yaw)) + 1e-6;
        double yaw_d2 = std::numeric_limits<double>::infinity();
        double anchor = 0.0;
        float yaw = 0.0F;
        std::uint16_t mask = 0;
        if (std::isfinite(yaw_reach)) {
          index.within(x, y, yaw_reach, [&](const Positioned& p) {
            const double d = (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y);
            if (p.has_yaw && d < yaw_d2) {
              yaw_d2 = d;
              anchor = p.yaw_rad;
            }
          });
          const double h = report.bandwidth_m;
          const double reach = yaw_reach + 2.0 * std::max(h, report.heading_bandwidth_m);
          // The coverage: the headings of the frames weighed at least e^-2 of the nearest's.
          // With heading terms from a wide kernel, those that kernel weighs so.
          const double hc = std::max(h, report.heading_bandwidth_m);
          const double cover_d2 = yaw_reach * yaw_reach + 4.0 * hc * hc;
          double sin_sum = 0.0, cos_sum = 0.0;
          index.within(x, y, reach, [&](const Positioned& p) {
            if (!p.has_yaw) return;
            const double d = (p.x_m - x) * (p.x_m - x) + (p.y_m - y) * (p.y_m - y);
            if (cover && d <= cover_d2)
              mask |= frame_sectors[static_cast<std::size_t>(&p - frames.data())];
            if (std::cos(p.yaw_rad - anchor) < kSamePassCos) return;
            const double w = std::exp(-(d - yaw_d2) / (2.0 * h * h));
            sin_sum += w * std::sin(p.yaw_rad);
            cos_sum += w * std::cos(p.yaw_rad);
          });
          yaw = static_cast<float>(
              sin_sum * sin_sum + cos_sum * cos_sum > 0.0 ? std::atan2(sin_sum, cos_sum) : anchor);
        }
        out.heading_rad[at] = yaw;
        if (cover) {
          out.heading_cover[at] = mask;
          if (std::sqrt(d2) <= report.bandwidth_m) {
            ++known_cells;
            known_sectors += static_cast<std::size_t>(__builtin_popcount(mask));
          }
        }
      }
    }
  }
  report.covered_heading_fraction =
      known_cells > 0 ? static_cast<double>(known_sectors) /
                            static_cast<double>(known_cells * ForwardMap::kHeadingSectors)
                      : 0.0;
  if (law != nullptr && report.has_heading)
    fit_bearings(frames, comparable, index, vectors, board_count, opt, law, board_places, x0, y0,
                 cell, out, report);
  return report;
}

}  // namespace harmoloc::sim_host::forward_map_training_detail
