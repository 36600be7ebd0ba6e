#pragma once
/// @file The robust observation model: one likelihood term per board (Guo & Li 2013 multiplies one
/// Gaussian per landmark), each a mixture of "the board is where the map says" and "something
/// else" (occluded, moved, lit differently) in the spirit of Cheng et al.:
///
///   l_b(x, y) = w_b exp(-s_b^2 r_b^2 / 2) + (1 - w_b) c,   r_b = (o_b - mu_b(x, y)) / (k sigma_b)
///
/// mu_b and sigma_b come from the forward map, k inflates sigma because successive frames share
/// most of their error, c is the floor of the "something else" component. w_b is the board's
/// motion index (probability that it is static and visible), estimated from its recent
/// residuals (an EM step with forgetting); s_b is Cheng et al.'s dynamic covariance scaling,
/// s = min(1, 2 Phi / (Phi + chi2)), evaluated at the filter's estimate, but only while most
/// boards agree with that estimate (a consensus): when most disagree, the pose is wrong, not the
/// boards, and every board keeps its full weight so that the filter (or the kidnap test) can
/// act on it. A route term multiplies in: the map knows only the places the training run went,
/// so a particle far from them is unlikely (docs/filter.md).

#include <array>
#include <cstddef>
#include <cstdint>

#include "harmoloc/algorithms/forward_map.hpp"
#include "harmoloc/algorithms/geometry.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

/// Every board's area in one frame, in the map's feature units (area_scale x pixels), and the
/// image angle of the boards that give a bearing (board_image_angle).
struct BoardFeatures {
  std::array<float, kMaxBoards> value{};
  std::size_t count = 0;
  std::array<float, kMaxBoards> angle_rad{};  ///< where bit b of angle_mask is set
  std::uint32_t angle_mask = 0;
  /// Bit b set when board b touches the frame's left or right side (AreaVector::side_pixels):
  /// the frame cuts it, and its area depends on exactly where the side falls across it.
  std::uint32_t cut_mask = 0;
};

BoardFeatures board_features(float area_scale, const AreaVector& areas);
/// The same with the image angles under @p map's law (none when the map has no bearings).
BoardFeatures board_features(const ForwardMap& map, float area_scale, const AreaVector& areas);

/// The largest feature the forward map expects for each board anywhere on its grid (0 for the
/// boards it does not model). Computed once, at start-up.
std::array<float, kMaxBoards> board_maxima(const ForwardMap& map);

/// Whether more than half of the modelled boards show more than @p ratio times their maximum
/// (BoardModelParams::implausible_ratio): no place on the map can look like that. False when
/// @p ratio is 0 or the map models no board.
bool frame_implausible(const ForwardMap& map, const std::array<float, kMaxBoards>& maxima,
                       const BoardFeatures& observed, double ratio);

struct BoardModelParams {
  double sigma_scale = 3.0;  ///< k: inflation of the forward map's per-board sigma
  /// The boards' joint likelihood is raised to 1 / this power: successive frames share most of
  /// their error (the same place, the same map error), so one frame is worth a fraction of an
  /// independent observation. The robust tests use k sigma; only the weight is tempered.
  double tempering = 40.0;
  double outlier_floor = 0.01;  ///< c: likelihood of "something else", relative to a perfect fit
  /// The kidnap test's likelihood of a board that shows less than expected: it may be hidden (a
  /// person, a box), which is likelier than an arbitrary outlier (board_preference).
  double hidden_floor = 0.1;
  /// The area noise of a board the frame's side cuts (BoardFeatures::cut_mask), in multiples of
  /// its trained noise; 0: such a board's area is not weighed at all.
  double cut_board_width = 1.0;
  double dcs_phi = 1.0;         ///< Cheng et al.'s Phi
  double consensus_chi2 = 9.0;  ///< a board agrees with the estimate when its chi2 is below
  /// More than this share of the modelled boards must agree: a majority (4 of 6 or 7, 5 of 8).
  double consensus_fraction = 0.5;
  double motion_index_rate = 0.05;  ///< weight of one frame in the motion index (forgetting)
  /// The same while the index rises, for a board that showed a sign of a move since it was last
  /// trusted (more area than expected, or a bearing off with no area missing; an occlusion only
  /// hides). A quarter of the fall: such a board must fit for about 1.9 s before it is trusted
  /// again, so a moved board that fits by chance for half a second stays written off
  /// (docs/filter.md).
  double motion_index_rise_rate = 0.0125;
  double motion_index_min = 0.02;  ///< bounds, so that a board can always come back
  double motion_index_max = 0.98;
  double route_free_m = 0.03;   ///< distance from the training run that costs nothing
  double route_sigma_m = 0.03;  ///< beyond it, a Gaussian fall-off of this width
  /// The same for the heading, where the map holds the training run's (ForwardMap::has_heading):
  /// the map knows the boards' areas only as seen along the route, so a particle turned away
  /// from the route's heading is as unlikely as one beside the route. Without it the heading is
  /// seen only through the route term, once a wrong heading has carried a particle off the
  /// route, and a heading error that builds up slowly is never taken back.
  double route_heading_free_deg = 5.0;   ///< heading difference that costs nothing
  double route_heading_sigma_deg = 5.0;  ///< beyond it, a Gaussian fall-off (0: no heading term)
  bool robust = true;  ///< false: Guo & Li's plain product of Gaussians (w = 1, s = 1)
  /// Where the map holds the boards' bearings (ForwardMap::has_bearings): each board that gives
  /// a bearing this frame also weighs the particles by where it appears across the frame, with
  /// the trained spread of its bearing widened by sigma_scale, in the same mixture (its motion
  /// index and scaling) and tempering as its area.
  bool bearings = true;
  /// How far from the estimate a board's area may be explained when the boards are assessed
  /// (consensus, motion index, scaling): the spread between passes of the training run over
  /// one place, from the map's calibration (0: at the estimate only). Where a board's area
  /// changes steeply with position (entering the field of view), a centimetre of wander is many
  /// sigma; that is no reason to distrust the board.
  double position_spread_m = 0.0;
  /// A frame in which more than half of the modelled boards show more than this many times the
  /// largest area the forward map expects for them anywhere is no view of the mapped scene (a
  /// frame of noise, a blinded sensor): it is not used. 0 turns the check off.
  double implausible_ratio = 2.0;
};

/// The factor board @p b's area noise is widened by in @p observed: 1 for a board seen whole,
/// BoardModelParams::cut_board_width for one the frame's side cuts (0: not weighed).
inline double cut_width(const BoardFeatures& observed, const BoardModelParams& params,
                        std::size_t b) {
  return ((observed.cut_mask >> b) & 1U) != 0U ? params.cut_board_width : 1.0;
}

/// A projected quantity (a board's image angle or feature) as a quadratic of the pose's offset
/// from the estimate (dx, dy in metres, dyaw in radians), within reach_m along x and y and
/// reach_rad along the heading (BoardUpdate::near_at).
struct NearQuadratic {
  /// q[0] + dx (q[1] + q[4] dx + q[7] dy + q[8] dyaw) + dy (q[2] + q[5] dy + q[9] dyaw)
  ///      + dyaw (q[3] + q[6] dyaw)
  std::array<float, 10> q{};
  float reach_m = 0.0F;
  float reach_rad = 0.0F;

  /// Whether an offset of at most @p off_m along x and y and @p off_rad along the heading is
  /// within the reach.
  bool covers(float off_m, float off_rad) const { return off_m <= reach_m && off_rad <= reach_rad; }
  float at(float dx, float dy, float dyaw) const { return value(q, dx, dy, dyaw); }
  /// The quadratic with coefficients @p c at an offset, in @p T (the fit checks it in double).
  template <typename T>
  static T value(const std::array<T, 10>& c, T dx, T dy, T dyaw) {
    return c[0] + dx * (c[1] + c[4] * dx + c[7] * dy + c[8] * dyaw) +
           dy * (c[2] + c[5] * dy + c[9] * dyaw) + dyaw * (c[3] + c[6] * dyaw);
  }
};

/// What the particle filter needs for one update: per board, the mixture's weights and the
/// (scaled) Gaussian width; the route term.
struct BoardUpdate {
  const ForwardMap* map = nullptr;
  std::size_t boards = 0;
  std::array<float, kMaxBoards> observed{};
  std::array<bool, kMaxBoards> use{};           ///< boards that take part (modelled ones)
  std::array<float, kMaxBoards> gain{};         ///< w_b
  std::array<float, kMaxBoards> floor{};        ///< (1 - w_b) c
  std::array<float, kMaxBoards> inv_two_var{};  ///< s_b^2 / (2 k^2 sigma_b^2)
  /// Boards taking part whose areas come from the map's projection (bit b; projects_area).
  std::uint32_t area_projection_mask = 0;
  /// Boards whose bearing takes part this frame (bit b), their image angle and
  /// s_b^2 / (2 k^2 sigma_bearing_b^2).
  std::uint32_t bearing_mask = 0;
  std::array<float, kMaxBoards> angle_rad{};
  std::array<float, kMaxBoards> bearing_inv_two_var{};
  /// Projected bearings and areas (projected_bearing.hpp) near the estimate (near_at), read from
  /// a quadratic there instead of the outline projected at each particle (NearQuadratic): board
  /// b of near_bearing_mask is expected at image angle near_bearing[b].at(dx, dy, dyaw) within
  /// its reach, board b of near_area_mask to show feature near_area[b].at(...). The reach
  /// follows the cloud's spread: two sigma, from kNearReach_m and kNearReach_rad up to 15 cm and
  /// 10 degrees, so that a wide cloud too is mostly read from the quadratic. A quadratic is
  /// taken only where it misses the projection at the reach's corners by at most kNearTolerance
  /// of the noise the particles are weighed with (the bearing's spread; the area's noise
  /// widened by the cloud's spread), else over half that reach, else over the narrowest: a board
  /// the frame's side cuts within the reach usually does not fit, and is projected at each
  /// particle. A quadratic, not a straight line: an area changes as the inverse square of the
  /// distance, and a line over 3 cm misses a board 1.25 m away by a third of its noise.
  static constexpr float kNearReach_m = 0.03F;
  static constexpr float kNearReach_rad = 0.035F;  // 2 degrees
  static constexpr float kNearTolerance = 0.25F;
  Pose2 near_at{};
  std::uint32_t near_bearing_mask = 0;
  std::array<NearQuadratic, kMaxBoards> near_bearing{};
  std::uint32_t near_area_mask = 0;
  std::array<NearQuadratic, kMaxBoards> near_area{};
  double inv_tempering = 1.0;  ///< exponent of the boards' joint likelihood
  float route_free_m = 0.0F;
  float route_inv_two_var = 0.0F;
  float heading_free_rad = 0.0F;
  float heading_inv_two_var = 0.0F;  ///< 0: no heading term
};

/// How the boards relate to the filter's estimate this frame.
struct BoardAssessment {
  /// (o_b - mu_b(estimate))^2 / (k sigma_b)^2, plus bearing_chi2[b]: a board disagrees with the
  /// estimate when where it appears does not fit, as when its area does not.
  std::array<float, kMaxBoards> chi2{};
  /// The bearing's share of chi2: (yaw - angle_b - phi_b(estimate))^2 / (k sigma_bearing_b)^2
  /// with the estimate's heading, for the boards that give a bearing this frame (0 for others).
  /// A board moved along its wall keeps its area; only its bearing gives it away.
  std::array<float, kMaxBoards> bearing_chi2{};
  std::array<float, kMaxBoards> scaling{};  ///< Cheng et al.'s s_b (1 without consensus)
  std::size_t modelled = 0;                 ///< boards the map models
  std::size_t agreeing = 0;                 ///< of those, with chi2 below the consensus bound
  /// Of the disagreeing boards, those showing more area than expected: something an occlusion
  /// cannot do (it only hides), so a sign that the estimate itself is wrong.
  std::size_t exceeding = 0;
  bool consensus = false;  ///< enough boards agree with the estimate
};

/// How much better the boards fit place a than place b: the sum over the modelled boards of
/// log(l(a) / l(b)), l = exp(-chi2 / 2) + c with chi2 in the trained sigma (the robust term with
/// every board trusted, so that no board can contribute more than ln(1 / c)). Nats; positive when a
/// fits better. A board that shows less than place b expects may be hidden there: at b it costs
/// at most ln(1 / hidden_floor) instead of ln(1 / c), so that one or two hidden boards cannot
/// make the estimate look wrong. For the kidnap test: do the boards prefer the global fix (a)
/// to the estimate (b)? Boards whose bit is set in @p leave_out do not count (those the filter
/// has found moved or hidden: a board a person is walking away from is still partly hidden, and
/// with three boards its shortfall alone can favour a place a few centimetres off). Both places
/// are seen at heading @p yaw_rad (what a map with heading terms expects depends on it).
///
/// Where the map holds bearings (and params.bearings), each board seen whole adds the same
/// robust log-ratio for its bearing, free of the heading: at each place the heading is the one
/// most boards' bearings agree on (each implies one: its image angle plus the map's world bearing
/// there), and a board's chi2 is its disagreement with it in the trained bearing sigma. A hidden
/// board shows no bearing, so a robot carried to where the boards look smaller (which the area
/// terms let cost the estimate little) is still told apart; with fewer than two such boards the
/// bearings say nothing.
double board_preference(const ForwardMap& map, const BoardFeatures& observed, double ax_m,
                        double ay_m, double bx_m, double by_m, const BoardModelParams& params,
                        std::uint32_t leave_out = 0, double yaw_rad = 0.0);

/// The place near a fix that the boards prefer most to place b, and by how much (nats).
struct PlacePreference {
  double nats = 0.0;
  double x_m = 0.0, y_m = 0.0;
};

/// board_preference of the best place within @p radius_m of (@p ax_m, @p ay_m) (on a grid of at
/// most 25 x 25 places, only those on the trained route: within route_free_m + 2 route_sigma_m
/// of it, and at least @p min_distance_m from place b), the fix's own place included whatever
/// its route distance. For the kidnap test: a fix can be off by more than its training error
/// where few boards are in view (three boards at 320 x 240: 18 cm at a place the boards told
/// apart), and the boards then fit the fix's own place no better than the estimate's although
/// they fit the robot's place well.
PlacePreference board_preference_near(const ForwardMap& map, const BoardFeatures& observed,
                                      double ax_m, double ay_m, double radius_m, double bx_m,
                                      double by_m, double min_distance_m,
                                      const BoardModelParams& params, std::uint32_t leave_out = 0,
                                      double yaw_rad = 0.0);

/// The per-board state that lives from frame to frame: each board's motion index.
class BoardReliability {
 public:
  /// Every board starts as static (motion index at its maximum).
  void reset(const BoardModelParams& params);

  /// Compares @p observed with what @p map expects at @p estimate (its heading too, for the
  /// bearings) and fills @p update for the particle filter. With consensus, the motion indices
  /// learn from this frame first. @p yaw_variance_rad2 is the estimate's own heading
  /// uncertainty (the cloud's spread): a bearing is judged against it as well as against the
  /// board's widened spread, so that right after a re-seed, when the cloud's headings are
  /// still spread, the boards that give a bearing are not taken for moved ones.
  /// @p position_sigma_m is the cloud's spread in position (metres): where the map projects a
  /// board's areas, their noise is widened by half the range of the projected area over the
  /// estimate moved that far (at most 0.5 m) along x and y, for the weights and the board's chi2
  /// alike. A projection is sharp (0.2-1% of the area): against a cloud tens of centimetres wide
  /// the board that fits one line of places best outweighs the others, which all read as
  /// outliers, and the cloud follows that line (random floor 6, docs/filter.md).
  /// With @p particles (the cloud's count; 0: as the spread) the weights are widened over the
  /// particles' bandwidth instead, the spread times (4 / (5 particles))^(1/7) (Silverman's rule
  /// for a kernel density in x, y and the heading), and the chi2 over the whole spread: a point
  /// of the cloud need not fit worse than its neighbours' spacing, but weighed over the whole
  /// spread the cloud could not tell its own places apart, and a re-seed a few centimetres off
  /// stayed there (docs/filter.md).
  BoardAssessment assess(const ForwardMap& map, const BoardFeatures& observed,
                         const Pose2& estimate, const BoardModelParams& params, BoardUpdate& update,
                         double yaw_variance_rad2 = 0.0, double position_sigma_m = 0.0,
                         std::size_t particles = 0);

  /// Motion index of board @p b: probability that it is static and visible.
  double static_probability(std::size_t b) const { return static_probability_[b]; }
  /// Boards whose motion index is below one half (for the masked harmonic fix).
  bool distrusted(std::size_t b) const { return static_probability_[b] < 0.5; }

 private:
  std::array<double, kMaxBoards> static_probability_{};
  /// Whether the board, since it was last trusted, showed a sign of a move that no occlusion
  /// gives (more area than the map expects, or a bearing off with no area missing): only then
  /// does its index rise at motion_index_rise_rate.
  std::array<bool, kMaxBoards> moved_{};
};

}  // namespace harmoloc::algorithms
