#pragma once
/// @file The forward map: from a position on the floor to the area each board should show there
/// (the inverse direction of the harmonic localizer), on a regular grid over the trained region
/// of which only the tiles near the training run are stored.
/// The particle filter weighs every particle by how well each board's measured area fits what
/// the map expects at the particle's position, board by board, so that one occluded or moved
/// board can be recognised and ignored (board_observation.hpp). Learned by the trainer from the
/// training run; stored in the map file (docs/map-format.md). Fixed capacity.

#include <array>
#include <cstddef>
#include <cstdint>
#include <new>

#include "harmoloc/algorithms/projected_bearing.hpp"
#include "harmoloc/algorithms/segmentation.hpp"

namespace harmoloc::algorithms {

#ifndef HARMOLOC_FORWARD_MAP_MAX_TILES
/// Tiles a forward map may store (a board's build may set fewer: the bare-metal kernels do).
#define HARMOLOC_FORWARD_MAP_MAX_TILES 640
#endif
#ifndef HARMOLOC_FORWARD_MAP_BEARINGS
/// Whether the forward map has room for the boards' bearings (1). A board's build may leave them
/// out (0: the bare-metal kernels do, to fit 256 KiB); it then refuses a map that holds them.
#define HARMOLOC_FORWARD_MAP_BEARINGS 1
#endif
#ifndef HARMOLOC_FORWARD_MAP_HEADING_TERMS
/// Whether the forward map has room for the heading terms of a floor map (1). A board's build
/// may leave them out (0: the bare-metal kernels do); it then refuses a map that holds them.
#define HARMOLOC_FORWARD_MAP_HEADING_TERMS 1
#endif
#ifndef HARMOLOC_FORWARD_MAP_MAX_TILE_GRID
/// Tile positions the grid may span (stored or not): 128 x 128 tiles of 16 cm at 2 cm cells.
#define HARMOLOC_FORWARD_MAP_MAX_TILE_GRID 16384
#endif

/// A regular grid of cells over the trained region, stored in square tiles of kTileSide cells:
/// only the tiles near the training run are kept (a route is a thin band through a room; a dense
/// grid over its bounding box spent most of its cells on floor the robot never crossed and had
/// to coarsen them to 12 cm on a 10 m route). A position in a tile that is not stored lies
/// farther from the training run than the trainer's margin: its cells read as the void cell, far
/// from the route, so the route term rules such a particle out.
struct ForwardMap {
  static constexpr std::uint32_t kTileSide = 8;
  static constexpr std::size_t kTileCells = kTileSide * kTileSide;
  static constexpr std::size_t kMaxTiles = HARMOLOC_FORWARD_MAP_MAX_TILES;
  static constexpr std::size_t kMaxCells = kMaxTiles * kTileCells;  ///< stored cells
  static constexpr std::size_t kMaxTileGrid = HARMOLOC_FORWARD_MAP_MAX_TILE_GRID;
  static constexpr std::size_t kMaxDimension = 8192;  ///< columns and rows each
  static constexpr std::uint16_t kNoTile = 0xFFFF;
  /// Storage index of the void cell: what a cell of a tile that is not stored reads as.
  static constexpr std::size_t kVoidCell = kMaxCells;
  /// The void cell's distance to the training run (metres).
  static constexpr float kVoidRouteDistance_m = 1.0e3F;
  static_assert(kMaxTiles < kNoTile, "tile slots are 16-bit");

  /// Grid: cell (c, r) is centred on (origin_x_m + c cell_m, origin_y_m + r cell_m). Values
  /// between centres are bilinear; positions beyond the grid take the border value.
  std::uint32_t columns = 0;  ///< 0: the map has no forward model
  std::uint32_t rows = 0;
  float origin_x_m = 0.0F;
  float origin_y_m = 0.0F;
  float cell_m = 0.0F;
  /// One entry per board of the threshold set (features in the harmonic model's units,
  /// area_scale x pixels). A board with sigma 0 is not modelled (never seen in training).
  std::uint32_t board_count = 0;
  std::array<float, kMaxBoards> sigma{};
  /// Whether heading_rad holds the training run's heading (labels with orientation).
  bool has_heading = false;

  /// The tile grid: tile (tc, tr) holds cells tc kTileSide.. and tr kTileSide..; its slot in
  /// the storage below, or kNoTile. Slots are numbered in row-major order of the stored tiles.
  std::uint32_t tile_columns = 0;
  std::uint32_t tile_rows = 0;
  std::uint32_t tile_count = 0;  ///< stored tiles
  std::array<std::uint16_t, kMaxTileGrid> tile_slot{};

  /// Per stored cell (storage index: slot x kTileCells + row-in-tile x kTileSide + column-in-tile)
  /// and one more, the void cell. The expected feature of every board at the cell's centre,
  /// kMaxBoards a cell.
  std::array<float, (kMaxCells + 1) * kMaxBoards> expected{};
  /// Distance from the cell centre to the nearest position of the training run (metres): how
  /// far the map's knowledge is from this place.
  std::array<float, kMaxCells + 1> route_distance_m{};
  /// The training run's heading near the cell (yaw, radians), where has_heading.
  std::array<float, kMaxCells + 1> heading_rad{};

  /// Board bearings (map version 6; docs/bearings.md): the lens's column-to-angle law learnt
  /// from the training run, and per stored cell the world bearing of every board as the training
  /// run saw it from near the cell: yaw - angle(centroid column). Heading-independent, like the
  /// areas. A particle at the cell with heading yaw expects board b at image angle
  /// yaw - bearing_rad; the observed angle comes from the law.
  bool has_bearings = false;
  /// The law: angle_rad(t) = a1 t + a3 t^3 with t = (u - (W - 1) / 2) / W for centroid column u
  /// in a frame W pixels wide (positive to the right of the optical axis).
  float bearing_a1_rad = 0.0F;
  float bearing_a3_rad = 0.0F;
  /// Where the cells' bearings are seen from (map version 9): the camera's place, this far ahead
  /// of the axle along the heading (metres), so that a cell's bearing holds at every heading and
  /// the trainer takes it from frames of every heading; 0: the axle's place (maps before 9, and
  /// training runs whose camera offset was not given).
  float bearing_camera_forward_m = 0.0F;
  /// Per board, the spread of its world bearing between passes over one place (radians); 0: the
  /// board's bearings are not modelled.
  std::array<float, kMaxBoards> bearing_sigma_rad{};
  /// What bearing_rad holds where the training run did not see the board whole near the cell.
  static constexpr float kNoBearing = 8.0F;
  /// Whether this build holds bearings (HARMOLOC_FORWARD_MAP_BEARINGS).
  static constexpr bool kBearingStorage = HARMOLOC_FORWARD_MAP_BEARINGS != 0;
  /// Per stored cell and the void cell, kMaxBoards a cell, in [-pi, pi] or kNoBearing (one cell
  /// only, never read, without kBearingStorage).
  std::array<float, (kBearingStorage ? kMaxCells + 1 : 1) * kMaxBoards> bearing_rad{};

  /// Heading terms (map version 7): where the training run drove a place at several headings
  /// (a floor), what the camera sees there depends on the heading too; each stored cell then
  /// holds, per board, the first harmonic of the area over the heading: the board's expected
  /// feature at heading yaw is expected + c cos(yaw) + s sin(yaw) (at least 0). The trainer fits
  /// them only where they predict other passes better (docs/filter.md); a route map has none.
  bool has_heading_terms = false;
  /// Whether this build holds heading terms (HARMOLOC_FORWARD_MAP_HEADING_TERMS).
  static constexpr bool kHeadingTermStorage = HARMOLOC_FORWARD_MAP_HEADING_TERMS != 0;
  /// Per stored cell and the void cell (one cell only without kHeadingTermStorage), per board:
  /// c, s (2 kMaxBoards a cell).
  std::array<float, (kHeadingTermStorage ? kMaxCells + 1 : 1) * kMaxBoards * 2> heading_terms{};

  /// Heading coverage (map version 8; docs/filter.md): the circle of headings in kHeadingSectors
  /// equal sectors, sector k from -pi + k kHeadingSector_rad. Per stored cell, bit k is set when
  /// the training run drove near the cell at a heading within kHeadingReach_rad of sector k's
  /// centre ("near": the frames the forward map's kernel weighs at the cell). The heading terms
  /// are a first harmonic fitted from those headings: beyond them it extrapolates, so where a
  /// heading keeps to the coverage (SeenHeading) one outside the covered sectors is evaluated at
  /// their nearest edge. 0: the cell holds no coverage (the void cell, maps before version 8).
  /// Built without kHeadingTermStorage, the coverage is read and not kept (one cell only).
  bool has_heading_coverage = false;
  static constexpr int kHeadingSectors = 16;
  static constexpr float kHeadingSector_rad = 2.0F * 3.14159265358979F / kHeadingSectors;
  /// How far from a heading it drove the training run covers: a first harmonic fitted from one
  /// heading and turned 45 degrees changes by at most 1 - cos 45 = 29% of its amplitude.
  static constexpr float kHeadingReach_rad = 3.14159265358979F / 4.0F;
  std::array<std::uint16_t, kHeadingTermStorage ? kMaxCells + 1 : 1> heading_cover{};

  /// Visibility (map version 10; docs/filter.md), instead of heading terms: what a board shows
  /// depends on the heading mostly through whether the lens sees it. Each stored cell then holds
  /// in heading_terms' storage, per board, the board's feature when seen whole from the camera's
  /// place at the cell and its angular half-width there (radians): seen at image angle
  /// a = yaw - bearing, it shows that feature times clamp((half_fov - |a|) / (2 half_width) +
  /// 1/2, 0, 1), half_fov from the bearings' law. Only where the cell holds the board's bearing
  /// (seen from the camera's place); elsewhere the cell's expected feature holds. Needs bearings
  /// seen from the camera's place; not with heading terms.
  bool has_visibility = false;
  /// How a board's feature grows towards the frame's edge (the projection stretches it there;
  /// distortion and vignetting change it as well): seen whole at image angle a it shows the
  /// cell's feature times 1 + visibility_angle_gain a^2 (angle_gain; at least 1/4). Measured by
  /// the trainer over the training run.
  float visibility_angle_gain = 0.0F;
  /// Where that stretch is centred (map version 14): the optical axis's image angle under the
  /// bearings' law (radians, positive to the right). The law's angles start at the frame's centre
  /// column, the lens's stretch and vignetting at its principal point (on a random floor 25 px
  /// apart at 1280 px, 1.8 degrees). 0: at the centre column (maps before version 14, and laws
  /// triangulated from the frames, which do not know the axis).
  float visibility_axis_rad = 0.0F;

  /// Projected bearings (map version 15; projected_bearing.hpp): the fitted camera and the
  /// outlines of the boards whose fit holds. A board with an outline takes its expected bearing
  /// from the projection at each particle's pose instead of from the cells. Needs bearings.
  BearingProjection projection;

  bool present() const { return columns > 0 && rows > 0; }
  /// Stored cells (whole tiles, including the cells of border tiles beyond the grid).
  std::size_t stored_cells() const { return static_cast<std::size_t>(tile_count) * kTileCells; }
  /// Storage index of cell (c, r) (within the grid), kVoidCell when its tile is not stored.
  std::size_t index(std::uint32_t c, std::uint32_t r) const {
    const std::uint16_t slot = tile_slot[(r / kTileSide) * tile_columns + c / kTileSide];
    if (slot == kNoTile) return kVoidCell;
    return static_cast<std::size_t>(slot) * kTileCells + (r % kTileSide) * kTileSide +
           c % kTileSide;
  }
  bool stored(std::uint32_t c, std::uint32_t r) const { return index(c, r) != kVoidCell; }
  /// The expected features of cell (c, r); the void cell's when its tile is not stored.
  float* cell(std::uint32_t c, std::uint32_t r) {
    return expected.data() + index(c, r) * kMaxBoards;
  }
  const float* cell(std::uint32_t c, std::uint32_t r) const {
    return expected.data() + index(c, r) * kMaxBoards;
  }
};

/// Puts @p object back to a value-initialised T in place: a map object is megabytes, and an
/// assignment from a temporary would put a second one on the stack.
template <class T>
void reset_in_place(T& object) {
  object.~T();
  ::new (static_cast<void*>(&object)) T();
}

/// A board's centroid column gives a bearing only with at least this many pixels and none on
/// the frame's left or right edge (a blob the frame cuts has its centroid pulled inwards); the
/// trainer and the firmware use the same rule.
constexpr std::uint32_t kBearingMinPixels = 30;

/// Whether board @p b of @p areas gives a bearing by that rule (columns measured, enough pixels,
/// none on the frame's left or right edge).
inline bool gives_bearing(const AreaVector& areas, std::size_t b) {
  return areas.columns_measured() && b < areas.count && areas.pixels[b] >= kBearingMinPixels &&
         !areas.cut_by_side(b);
}

/// The image angle of board @p b in @p areas under @p map's law (radians, positive to the right
/// of the optical axis); false when the board gives no bearing in this frame (columns not
/// measured, too small, cut by the frame) or the map has no law.
bool board_image_angle(const ForwardMap& map, const AreaVector& areas, std::size_t b,
                       float& angle_rad);

/// Tiles a grid of @p columns x @p rows cells needs along each axis.
constexpr std::uint32_t tiles_along(std::uint32_t cells) {
  return (cells + ForwardMap::kTileSide - 1U) / ForwardMap::kTileSide;
}

/// Lays out @p map's grid: @p columns x @p rows cells, the tiles @p stored marks (row-major over
/// the tile grid, non-zero: stored; nullptr: every tile). Every value is cleared and the void
/// cell set. Returns false, leaving the map without a grid, when the layout exceeds the map's
/// capacity (dimensions, tile grid, tiles) or stores no tile.
bool lay_out_grid(ForwardMap& map, std::uint32_t columns, std::uint32_t rows,
                  const std::uint8_t* stored = nullptr);

/// Where a position falls on the grid: the four surrounding cells and their bilinear weights.
struct GridPoint {
  std::uint32_t index[4];  ///< storage indices of the corners (ForwardMap::index)
  float weight[4];         ///< bilinear weights, summing to 1
  float outside_m;         ///< how far the position lies beyond the grid's border cells (0 inside)
};

/// Locates (@p x_m, @p y_m) on @p map's grid (clamped to the border). @p map must be present().
GridPoint locate(const ForwardMap& map, double x_m, double y_m);

/// The storage index of @p point's heaviest stored corner (ties: the first), kVoidCell when no
/// corner is stored: the cell whose per-cell values (route heading, heading coverage, fix error)
/// stand for the point.
std::size_t nearest_stored_cell(const GridPoint& point);

/// The expected features of all map.board_count boards at @p point (a map with heading terms:
/// their value over every heading, the terms left out).
void expected_features(const ForwardMap& map, const GridPoint& point, float* out);

/// A heading as the forward map reads it: its cosine and sine, its coverage sector
/// (ForwardMap::kHeadingSectors) and where in it, and whether to keep to the covered headings.
struct SeenHeading {
  float cos_yaw = 1.0F;
  float sin_yaw = 0.0F;
  int sector = 0;
  float within = 0.0F;   ///< where in its sector, 0 (its lower edge) to 1
  float yaw_rad = 0.0F;  ///< the heading itself, in [-pi, pi]
  /// Whether a cell reads it only within the headings it covers (else at their nearest edge).
  bool keep_to_coverage = true;
};

/// @p yaw_rad (any finite angle; not finite reads as 0) as the forward map reads it.
SeenHeading seen_heading(double yaw_rad);

/// The coverage sector of @p yaw_rad (any finite angle), 0..kHeadingSectors - 1.
int heading_sector(double yaw_rad);

/// The same seen at @p heading: with the map's heading terms where it has them (each at least
/// 0), each corner cell's terms at the heading itself where the cell covers it (or the heading
/// does not keep to the coverage), else at the nearest edge of its covered sectors.
void expected_features(const ForwardMap& map, const GridPoint& point, const SeenHeading& heading,
                       float* out);

/// Whether the map's coverage at @p point's heaviest stored corner holds @p heading (true for a
/// map without coverage; false for a point with no stored corner).
bool heading_covered(const ForwardMap& map, const GridPoint& point, const SeenHeading& heading);
/// The same for a pose: whether the map's coverage holds heading @p yaw_rad at (@p x_m, @p y_m);
/// true, without locating the pose, for a map without coverage.
bool heading_covered(const ForwardMap& map, double x_m, double y_m, double yaw_rad);

/// The distance to the training run at @p point (metres; bilinear, plus the distance beyond the
/// grid for a position outside it).
float route_distance(const ForwardMap& map, const GridPoint& point);

/// The training run's heading at the cell nearest (@p x_m, @p y_m); 0 when !map.has_heading.
float route_heading(const ForwardMap& map, double x_m, double y_m);
/// The same at @p point: the heading of its heaviest stored corner; false (and @p heading_rad
/// untouched) when the map has no heading or no corner of @p point is stored.
bool route_heading(const ForwardMap& map, const GridPoint& point, float& heading_rad);

/// The world bearing of board @p b expected at @p point (the stored cells' bilinear mean, over
/// the corners that hold one, taken around the first such corner so that the mean does not jump
/// at +-pi); false when no corner holds one.
bool expected_bearing(const ForwardMap& map, const GridPoint& point, std::size_t b,
                      float& bearing_rad);

/// The image angle at which the camera at @p camera (camera_at_pose of @p map's projection) sees
/// board @p b's centroid, from the board's outline in the projection under @p map's law (radians,
/// positive to the right; a centroid beyond the frame's side reads as 0.05 of the width past it);
/// false when the board has no outline or lies behind the camera or beyond the lens's image.
bool projected_image_angle(const ForwardMap& map, const CameraAtPose& camera, std::size_t b,
                           float& angle_rad);

/// The camera of a robot at one pose for projected_image_angle, placed (camera_at_pose) on first
/// use only: a pose whose boards are all read from the cells never places it.
class CameraOnce {
 public:
  CameraOnce(const BearingProjection& projection, double x_m, double y_m, double cos_yaw,
             double sin_yaw)
      : projection_(projection), x_m_(x_m), y_m_(y_m), cos_yaw_(cos_yaw), sin_yaw_(sin_yaw) {}
  const CameraAtPose& get() {
    if (!placed_) {
      camera_ = camera_at_pose(projection_, static_cast<float>(x_m_), static_cast<float>(y_m_),
                               static_cast<float>(cos_yaw_), static_cast<float>(sin_yaw_));
      placed_ = true;
    }
    return camera_;
  }

 private:
  const BearingProjection& projection_;
  double x_m_, y_m_, cos_yaw_, sin_yaw_;
  bool placed_ = false;
  CameraAtPose camera_{};
};

/// The image angle of a centroid at column @p column_px of @p map's projection, under @p map's
/// law: projected_image_angle for a column already projected (project_outline).
float image_angle_of_column(const ForwardMap& map, float column_px);

/// Whether board @p b's areas come from @p map's projection (an outline and its feature per
/// pixel).
inline bool projects_area(const ForwardMap& map, std::size_t b) {
  return b < kMaxBoards && map.projection.points[b] != 0U && map.projection.area_per_px[b] > 0.0F;
}

/// The noise the filter weighs board @p b's area with (feature units): the projection's own
/// where the board's areas are projected and the map holds that noise, else the map's sigma.
inline float weighed_area_sigma(const ForwardMap& map, std::size_t b) {
  return projects_area(map, b) && map.projection.area_sigma[b] > 0.0F ? map.projection.area_sigma[b]
                                                                      : map.sigma[b];
}

/// Whether any board's areas come from @p map's projection.
bool projects_areas(const ForwardMap& map);

/// For every board whose areas come from @p map's projection (projects_area), its feature seen
/// by the camera at @p camera (camera_at_pose of the projection), written to @p out[b]; the
/// other boards keep @p out's value. Only the boards of @p boards (bit b) when given.
void apply_projected_areas(const ForwardMap& map, const CameraAtPose& camera, float* out,
                           std::uint32_t boards = ~0U);

/// The spread the filter weighs board @p b's bearing with (radians): the projection's own where
/// the board's bearing is projected and the map holds that spread, else the cells'.
inline float weighed_bearing_sigma_rad(const ForwardMap& map, std::size_t b) {
  const BearingProjection& p = map.projection;
  return p.points[b] != 0U && p.sigma_rad[b] > 0.0F ? p.sigma_rad[b] : map.bearing_sigma_rad[b];
}

/// The lens's half field of view under @p map's bearing law (radians): the angle of a centroid
/// on the frame's left or right edge.
inline float half_field_of_view(const ForwardMap& map) {
  const float a = 0.5F * map.bearing_a1_rad + 0.125F * map.bearing_a3_rad;
  return a < 0.0F ? -a : a;
}

/// What a robot at (@p x_m, @p y_m) (@p point: that place on the grid, locate) facing @p heading
/// expects: expected_features at its place and, where the map has visibility, apply_visibility
/// at its camera's place; the boards whose areas the map projects, apply_projected_areas.
void expected_at_pose(const ForwardMap& map, const GridPoint& point, double x_m, double y_m,
                      const SeenHeading& heading, float* out);

/// What share of a board the lens sees (0..1) with its centre at @p abs_angle_rad (>= 0) from
/// the optical axis, the lens's half field of view @p half_fov_rad and the board's angular
/// half-width @p half_width_rad: half of it with its centre on the frame's edge (the soft edge
/// keeps the filter's weights smooth). A value that is not finite reads as 0.
inline float visible_share(float half_fov_rad, float half_width_rad, float abs_angle_rad) {
  const float seen = (half_fov_rad - abs_angle_rad) / (2.0F * half_width_rad + 1e-4F) + 0.5F;
  return seen > 1.0F ? 1.0F : (seen > 0.0F ? seen : 0.0F);
}

/// A board's feature seen whole at image angle @p angle_rad relative to its feature on the axis:
/// 1 + @p gain a^2, at least 1/4 (ForwardMap::visibility_angle_gain).
inline float angle_gain(float gain, float angle_rad) {
  const float g = 1.0F + gain * angle_rad * angle_rad;
  return g > 0.25F ? g : 0.25F;
}

/// The same under @p map's gain, centred on its optical axis: a board seen whole at image angle
/// @p angle_rad (from the law) shows its feature on the axis times this.
inline float visibility_gain(const ForwardMap& map, float angle_rad) {
  return angle_gain(map.visibility_angle_gain, angle_rad - map.visibility_axis_rad);
}

/// Where @p map has visibility: every board's feature as the camera at @p seen_from (its place,
/// bearing_point) facing @p yaw_rad sees it (the cell's feature on the axis, times visibility_gain
/// and visible_share at its image angle), written to @p out[b] for the boards whose bearing the
/// corners of @p seen_from hold (the others keep @p out's value). With @p bearing_rad, each board's
/// expected_bearing there as well (ForwardMap::kNoBearing where none), read on the way. Only the
/// boards of @p boards (bit b); the others' entries are left as they are.
void apply_visibility(const ForwardMap& map, const GridPoint& seen_from, float yaw_rad, float* out,
                      float* bearing_rad = nullptr, std::uint32_t boards = ~0U);

/// Where @p map's bearings are read for a robot at (@p x_m, @p y_m) facing (@p cos_yaw,
/// @p sin_yaw): the camera's place when the map's bearings are seen from it, else the axle's.
inline GridPoint bearing_point(const ForwardMap& map, double x_m, double y_m, double cos_yaw,
                               double sin_yaw) {
  const double d = static_cast<double>(map.bearing_camera_forward_m);
  return locate(map, x_m + d * cos_yaw, y_m + d * sin_yaw);
}

}  // namespace harmoloc::algorithms
