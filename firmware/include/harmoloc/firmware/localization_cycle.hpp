#pragma once
/// @file The fixed-rate cycle: acquire -> segment -> localize -> read encoders -> predict ->
/// update -> publish -> account time. One instance holds every buffer the cycle touches; it is
/// built at start-up and then never allocates. The publish stage also serves the link's inbound
/// side: the commands a peer sends (relocalize, set pose, request a message) are acted on and
/// answered there, before the cycle's own frames go out (mavlink_commands.cpp).

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "harmoloc/algorithms/fix_board_check.hpp"
#include "harmoloc/algorithms/fix_error_grid.hpp"
#include "harmoloc/algorithms/floor_search.hpp"
#include "harmoloc/algorithms/harmonic_localizer.hpp"
#include "harmoloc/algorithms/map_codec.hpp"
#include "harmoloc/algorithms/nearby_pose_test.hpp"
#include "harmoloc/algorithms/particle_filter.hpp"
#include "harmoloc/algorithms/segmentation.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/latency_histogram.hpp"
#include "harmoloc/firmware/latency_window.hpp"
#include "harmoloc/firmware/mavlink_inbound.hpp"
#include "harmoloc/firmware/mavlink_signing.hpp"
#include "harmoloc/firmware/mavlink_v2.hpp"
#include "harmoloc/firmware/pose_messages.hpp"
#include "harmoloc/firmware/pose_output.hpp"
#include "harmoloc/hal/camera.hpp"
#include "harmoloc/hal/clock.hpp"
#include "harmoloc/hal/persistent_record.hpp"
#include "harmoloc/hal/pose_link.hpp"
#include "harmoloc/hal/wheel_encoders.hpp"

namespace harmoloc::firmware {

enum class Stage : std::uint8_t {
  kAcquire,
  kSegment,
  kLocalize,
  kEncoders,
  kPredict,
  kUpdate,
  kPublish,
  kCycle
};
constexpr std::size_t kStageCount = 8;
const char* stage_name(Stage stage);

struct FixOutput {
  algorithms::HarmonicFix fix;
  algorithms::AreaVector areas;  ///< what the fix was computed from (recorded for training)
  bool present = false;          ///< a frame was localised this cycle
  /// Boards the filter distrusted in this frame's update (motion index below 1/2; bit b: board
  /// b), as the area log records them. 0 when the frame's boards were not weighed one by one
  /// (no forward map, filter not yet initialised, an implausible frame).
  std::uint32_t distrusted_mask = 0;
};

struct CycleCounters {
  std::uint64_t cycles = 0;
  std::uint64_t frames = 0;
  std::uint64_t no_frame = 0;
  std::uint64_t corrupt_frames = 0;
  std::uint64_t stale_frames = 0;  ///< frames stamped no later than the last one used (unused)
  std::uint64_t frame_size_mismatch = 0;
  std::uint64_t fixes_used = 0;
  std::uint64_t unknown_place = 0;
  std::uint64_t implausible_frames = 0;  ///< frames no place on the map can look like (unused)
  /// Cycles whose pose lay outside the mapped region plus filter.map_margin_m (published invalid).
  std::uint64_t off_map_cycles = 0;
  /// Cycles published odometry only (invalid without encoder data) because the map's heading
  /// coverage did not hold the estimate's heading at its place while frames were usable.
  std::uint64_t uncovered_cycles = 0;
  /// Cycles published odometry only (invalid without encoder data) because the frames' boards
  /// disagreed with the estimate and no fix the filter weighs vouched for it
  /// (HealthCause::kBoardsDisagree).
  std::uint64_t disagree_cycles = 0;
  /// Cycles published odometry only because the cloud's position spread was too wide
  /// (HealthCause::kSpreadWide, filter.nominal_spread_m).
  std::uint64_t spread_wide_cycles = 0;
  /// Frames whose fix left out a board the frame's side cut (algorithms::uncut_features()).
  std::uint64_t cut_board_frames = 0;
  std::uint64_t encoder_samples = 0;
  /// Encoder gaps the cloud spent diffusing (vision only), closed by their first sample: the
  /// cloud is moved to where the gap's travel takes the pose of the last sample before it.
  std::uint64_t encoder_gaps_bridged = 0;
  std::uint64_t overruns = 0;
  std::uint64_t overrun_alarms = 0;  ///< times the overrun alarm was raised
  std::uint64_t resamples = 0;
  /// The particle count over the cycles with an initialized filter: it changes only with
  /// KLD-sampling (filter.kld), and is the capacity otherwise.
  std::uint64_t particle_cycles = 0;
  std::uint64_t particles_sum = 0;
  std::uint64_t particles_min = 0;
  std::uint64_t particles_max = 0;
  std::uint64_t no_consensus = 0;       ///< frames whose boards mostly disagreed with the estimate
  std::uint64_t distrusted_boards = 0;  ///< sum over frames of boards below motion index 1/2
  /// Times the fix's board check found a board dragging the fix (algorithms/fix_board_check.hpp).
  std::uint64_t fix_board_suspicions = 0;
  std::uint64_t kidnap_triggers = 0;  ///< frames where Yang et al.'s change rate exceeded 0.5
  std::uint64_t kidnaps = 0;          ///< confirmed kidnaps (the filter was re-seeded)
  std::uint64_t lost = 0;             ///< of those, re-seeded over the whole map (no fix)
  /// Draws of particles around a nearby pose the boards kept preferring (floor maps): times,
  /// not particles.
  std::uint64_t nearby_draws = 0;
  std::uint64_t link_dropped = 0;
  std::array<std::uint64_t, 5> cycles_in_health{};

  /// Particles per cycle over the cycles with an initialized filter; 0 before the first.
  double particles_mean() const {
    return particle_cycles == 0
               ? 0.0
               : static_cast<double>(particles_sum) / static_cast<double>(particle_cycles);
  }
};

enum class CycleResult : std::uint8_t { kRan, kEnded };

/// What the kidnap test takes as its fix: the harmonic localizer's, or the floor search's pose
/// (kidnap.floor_search on a floor map with bearings).
enum class KidnapEvidence : std::uint8_t { kHarmonicFix, kFloorSearch };

/// The kidnap test's parameters with those left "auto" in the config (negative) derived from
/// what the evidence is: for the harmonic fix, from the map's calibration (how far a fix must
/// be, and how close successive fixes, measured against the fix's own error on the training
/// run); for the floor search, whose pose is good to a few centimetres, the values of maps
/// without a calibration.
algorithms::KidnapParams derived_kidnap_params(
    const algorithms::KidnapParams& configured, const algorithms::MapCalibration& calibration,
    KidnapEvidence evidence = KidnapEvidence::kHarmonicFix);

/// The geometry the odometry runs on: the configured one with the map's odometry calibration
/// applied (unless the config turns it off, or the map has none).
algorithms::DiffDriveGeometry effective_geometry(const FirmwareConfig& config,
                                                 const algorithms::MapCalibration& calibration);

/// One start-up line on the odometry calibration applied (or turned off); empty when the map
/// has none. Start-up only (allocates).
std::string odometry_summary(const FirmwareConfig& config,
                             const algorithms::MapCalibration& calibration);

/// Whether the particles are held to the training run's passes (the route term and the route
/// heading term): as observation.route_terms says, or by the map (off for a floor map).
bool route_terms_on(const FirmwareConfig& config, const algorithms::MapCalibration& calibration);

/// One start-up line when the route terms are off (a floor map, or the config); empty when they
/// are on. Start-up only (allocates).
std::string route_terms_summary(const FirmwareConfig& config,
                                const algorithms::MapCalibration& calibration);

/// Whether the harmonic fix weighs the particles (the fix term; it needs the map's calibration
/// as well): as observation.fix_term says, or by the map (off for a floor map: there the fix,
/// trained at the headings the coverage run drove, is many times further off at the others than
/// its calibration says; docs/filter.md).
bool fix_term_on(const FirmwareConfig& config, const algorithms::MapFile& map);

/// One start-up line when the map turns the fix term off (observation.fix_term = "auto"); empty
/// otherwise. Start-up only (allocates).
std::string fix_term_summary(const FirmwareConfig& config, const algorithms::MapFile& map);

/// Whether the filter adapts its particle count (KLD-sampling): as filter.kld says, or by the
/// map (on for a floor map: the 30-floor sweep backs it there; docs/filter.md).
bool kld_on(const FirmwareConfig& config, const algorithms::MapFile& map);

/// One start-up line when the map turns KLD-sampling on (filter.kld = "auto"); empty otherwise.
std::string kld_summary(const FirmwareConfig& config, const algorithms::MapFile& map);

class LocalizationCycle {
 public:
  /// @p map must outlive the cycle (the firmware keeps it in static storage). The colour table
  /// is built for @p pixel_format, the camera's (frames of the other format are still segmented
  /// exactly, only more slowly).
  LocalizationCycle(const FirmwareConfig& config, const algorithms::MapFile& map,
                    hal::Camera& camera, hal::WheelEncoders& encoders, hal::PoseLink& link,
                    const hal::Clock& clock,
                    hal::PixelFormat pixel_format = hal::PixelFormat::kRgb24);
  /// The cycle keeps a reference to @p config: a temporary would dangle after construction.
  LocalizationCycle(const FirmwareConfig&& config, const algorithms::MapFile& map,
                    hal::Camera& camera, hal::WheelEncoders& encoders, hal::PoseLink& link,
                    const hal::Clock& clock,
                    hal::PixelFormat pixel_format = hal::PixelFormat::kRgb24) = delete;

  /// Runs one cycle. The data clock follows the frames; a cycle without a frame advances it
  /// by one period. The camera is given until one period after the cycle's start.
  CycleResult run_once();
  /// The same with the camera's deadline given (CyclePacer::wait_for_cycle(): a period ahead
  /// when camera-paced, now when timer-paced, so that acquire does not wait).
  CycleResult run_once(std::uint64_t acquire_deadline_ns);

  const PoseOutput& pose() const { return pose_; }
  /// Whether the particles are weighed board by board (a forward map and that model chosen).
  bool uses_boards() const { return use_boards_; }
  /// On a floor map with bearings: whether the nearby pose test runs (filter.nearby_test), and
  /// whether the kidnap test takes the floor search's pose as its evidence (kidnap.floor_search).
  bool uses_nearby_test() const { return nearby_on_; }
  bool uses_floor_search() const { return floor_search_on_; }
  /// The particles the filter uses now (the capacity, `filter.particles`, unless KLD-sampling
  /// has adapted it).
  std::size_t particle_count() const { return filter_.size(); }
  /// Motion index of board @p b (probability that it is static and visible).
  double board_static_probability(std::size_t b) const {
    return reliability_.static_probability(b);
  }
  const algorithms::BoardAssessment& board_assessment() const { return assessment_; }
  /// The boards as the last frame weighed against the forward map showed them (features and
  /// image angles; nothing seen before the first such frame).
  const algorithms::BoardFeatures& board_observation() const { return observed_; }
  /// Frames whose boards were weighed against the forward map so far (board_observation()
  /// changed): a replay tells from it which cycles weighed the boards.
  std::uint64_t board_observations() const { return observations_; }
  /// The global fix the kidnap test compares with (computed without distrusted boards).
  const algorithms::HarmonicFix& robust_fix() const { return robust_fix_; }
  /// The check of the fix's boards (which it holds suspect).
  const algorithms::FixBoardCheck& fix_check() const { return fix_check_; }
  /// Yang et al.'s P of the last frame and what the detector made of it.
  double kidnap_probability() const { return kidnap_.probability(); }
  algorithms::KidnapVerdict kidnap_verdict() const { return kidnap_verdict_; }
  /// What the kidnap test saw this cycle (for tools that look at one run closely).
  const algorithms::KidnapInput& kidnap_input() const { return kidnap_input_; }
  /// On a floor: the pose the floor search follows (invalid elsewhere).
  const algorithms::FloorPose& floor_search_pose() const { return floor_fix_; }
  /// On a floor: the nearby pose test, as the latest frame left it.
  const algorithms::NearbyPoseTest& nearby_test() const { return nearby_; }
  /// The filter's board update of the latest frame weighed (its observation model).
  const algorithms::BoardUpdate& board_update() const { return board_update_; }
  const FixOutput& last_fix() const { return fix_; }
  const CycleCounters& counters() const { return counters_; }
  const LatencyHistogram& stage_histogram(Stage stage) const {
    return histograms_[static_cast<std::size_t>(stage)];
  }
  std::uint64_t budget_ns() const { return budget_ns_; }
  /// Live boards: from a frame's timestamp (its capture, on the monotonic clock) to the moment
  /// the ODOMETRY computed from it was handed to the link, once per cycle with a frame and a
  /// pose. What an autopilot's delay parameter (VISO_DELAY_MS, EKF2_EV_DELAY) is set from. Empty
  /// in replays (their frame times are the recording's). Each heartbeat period's median and
  /// maximum also go on the link (NAMED_VALUE_FLOAT c2s_p50_ms, c2s_max_ms, after the
  /// HEARTBEAT).
  const LatencyHistogram& capture_to_send() const { return capture_to_send_; }
  mavlink::InboundCounters inbound_counters() const { return receiver_.counters(); }

  /// Sets the link's signing clock to the wall time @p unix_time_us (start-up; a board without
  /// a real-time clock, link.signing_clock = "peer", leaves it: its first accepted signed frame
  /// sets it).
  void set_signing_time(std::uint64_t unix_time_us);
  /// Start-up, with a signing key: what the previous run persisted (nothing at or below its
  /// high-water mark is accepted), and where the cycle persists the state from now on (ahead
  /// of need, at most once a second; firmware/mavlink_signing.hpp). @p store may be nullptr.
  void restore_signing_state(const mavlink::SigningState& state, hal::PersistentRecord* store,
                             std::uint64_t durable_high_water);
  /// The signing state to write at a clean stop.
  mavlink::SigningState final_signing_state() const { return signer_.final_state(); }
  const mavlink::Signer& signer() const { return signer_; }

  /// Live boards (real devices): the data clock is the monotonic clock the devices stamp their
  /// data with. A cycle without a frame takes the clock's time instead of the last frame's time
  /// plus one period, and the data time never goes back; the whole-cycle time and the budget
  /// leave out the wait for the camera in acquire() (its own stage keeps it). Off (replay) by
  /// default.
  void set_live_clock(bool live) { live_clock_ = live; }

  /// Paced runs (a live board, or a replay at the recording's rate): cycle.overrun_alarm_cycles
  /// overruns in a row raise the overrun alarm (STATUSTEXT, HEARTBEAT at least CRITICAL) and as
  /// many cycles within the budget clear it (STATUSTEXT). Off by default: an unpaced replay
  /// counts its overruns but keeps them off the link, which stays deterministic.
  void set_overrun_alarm(bool enabled) { overrun_alarm_enabled_ = enabled; }
  bool overrun_alarm() const { return overrun_alarm_; }

 private:
  using Features = std::array<float, algorithms::HarmonicModel::kMaxFeatures>;
  /// The camera's part of one cycle: what acquire() gave, and whether it is a new frame of the
  /// map's size (usable).
  struct FrameIn {
    hal::FrameView frame{};
    hal::CameraStatus status = hal::CameraStatus::kNoFrame;
    bool have_frame = false;  ///< a frame, not stale (it must be released)
    bool usable = false;      ///< and of the map's image size
  };
  /// The encoders' part: the travel since the last sample, or the first sample after a gap.
  struct EncoderIn {
    algorithms::OdometryDelta delta{};
    double dt_s = 0.0;          ///< time between the samples of delta
    bool have_delta = false;    ///< delta holds the travel since the previous sample
    bool bridge_now = false;    ///< the first sample after a diffused gap: move the cloud
    bool fresh_sample = false;  ///< an encoder sample came in this cycle
  };

  /// One cycle: the stages below in order, each timed into its histogram.
  CycleResult run(std::uint64_t acquire_deadline_ns, bool have_deadline);
  /// After acquire: stale frames, the data clock, the frame counters.
  void take_frame(FrameIn& in, std::uint64_t cycle_start);
  /// The boards' pixel areas of a usable frame (none otherwise).
  void segment(const FrameIn& in, algorithms::AreaVector& areas);
  /// The harmonic fix (fix_) and the features it was computed from.
  void localize(bool usable, const algorithms::AreaVector& areas, Features& features);
  EncoderIn read_encoders();
  /// Moves the cloud by the travel (or bridges a gap, or diffuses without odometry).
  void predict(const EncoderIn& encoders);
  /// Weighs the cloud by the frame (or seeds it) and sets the pose and its health.
  void update(const algorithms::AreaVector& areas, const Features& features, bool fresh_sample);
  LatencyHistogram& histogram(Stage stage) { return histograms_[static_cast<std::size_t>(stage)]; }
  void account_overrun(bool overrun);
  void publish();
  /// The capture-to-send latencies since the last heartbeat, on the link (live boards).
  void report_capture_to_send();
  // The link's inbound side and the commands (mavlink_commands.cpp).
  void service_link();
  mavlink::MavResult execute(const mavlink::CommandLong& command, std::int32_t& result_param2);
  mavlink::MavResult relocalize(std::int32_t& how);
  mavlink::MavResult set_pose(const mavlink::CommandLong& command);
  mavlink::MavResult request_message(const mavlink::CommandLong& command);
  void send(std::size_t size);
  Health assess_health() const;
  // Sets the health the pose is published with and its cause: assess_health(), except that a
  // pose outside the mapped region (plus filter.map_margin_m) is invalid, never nominal; a health
  // that lacks vision while frames arrive whose estimate the heading coverage does not hold says
  // so (HealthCause::kHeadingNotCovered), as does one while frames arrive whose boards disagree
  // with the estimate (HealthCause::kBoardsDisagree).
  void set_published_health();
  bool off_map(const algorithms::Pose2& pose) const;
  // Whether a fix's place is finite and within the mapped region (off_map's test).
  bool fix_on_map(const algorithms::HarmonicFix& fix) const;
  // Whether a frame taken at @p t_ns is within cycle.camera_timeout_ms of the data clock.
  bool camera_fresh(std::uint64_t t_ns) const;
  // The measurement update with the per-board model; returns whether the frame counts as vision.
  bool update_with_boards(
      const algorithms::AreaVector& areas,
      const std::array<float, algorithms::HarmonicModel::kMaxFeatures>& features);
  // On a floor: the search's slice of this cycle and the pose it follows (floor_fix_), then the
  // kidnap test with that pose as its evidence. Both weigh every board (kFloorSearchLeaveOut).
  void follow_floor(const algorithms::BoardFeatures& observed);
  // The kidnap test's step on @p in (its counters; on "lost" the re-seed over the map and the
  // STATUSTEXT, on a kidnap the STATUSTEXT: the caller re-seeds).
  algorithms::KidnapVerdict step_kidnap_test(const algorithms::KidnapInput& in);
  void floor_kidnap_test(const algorithms::BoardFeatures& observed,
                         const algorithms::Pose2& estimate, double match);
  // Re-seeds: around a global fix (heading from the map where it knows one), around both the
  // boards' place and the fix's after a kidnap, or over the map; after_reseed() forgets what
  // was learnt against the old cloud.
  // The heading a seed at (x, y) starts from, its spread and whether it is unknown (uniform).
  struct SeedHeading {
    double yaw_rad = 0.0;
    double sigma_rad = 0.0;
    bool uniform = true;
    bool from_boards = false;  ///< from the frame's bearings (a floor map)
  };
  void reseed_around(double x_m, double y_m);
  // With the heading already found for (x, y): the first seed looks it up to decide whether to
  // wait for a frame with a bearing.
  void reseed_around(double x_m, double y_m, const SeedHeading& heading);
  void reseed_between(double place_x_m, double place_y_m, double fix_x_m, double fix_y_m);
  /// The cloud on the floor search's pose (floor_fix_, valid) and, where it is a known place
  /// apart from it, the harmonic fix: a floor kidnap's re-seed, and the first seed with
  /// filter.seed_from_search. @p sigma_m spreads the search's pose, @p fix_sigma_m the fix.
  void seed_from_search(double sigma_m, double fix_sigma_m, double yaw_sigma_rad);
  void reseed_globally();
  void after_reseed();
  // Whether the map knows the training run's heading (and the boards are used): a re-seed then
  // takes it at its centre, else the heading is left unknown.
  bool route_heading_known() const;
  SeedHeading seed_heading(double x_m, double y_m) const;
  void publish_pose_estimate();

  const FirmwareConfig& config_;
  const algorithms::MapFile& map_;
  hal::Camera& camera_;
  hal::WheelEncoders& encoders_;
  hal::PoseLink& link_;
  const hal::Clock& clock_;

  algorithms::BoardClassifier classifier_;
  // 16 MiB reserved at start-up, holding the table of the camera's pixel format only.
  std::unique_ptr<std::uint8_t[]> colour_table_storage_;
  algorithms::ColourTable colour_table_;
  algorithms::YuyvTable yuyv_table_;
  algorithms::ParticleFilter filter_;
  algorithms::BoardReliability reliability_;
  std::array<float, algorithms::kMaxBoards> board_maxima_{};  ///< per board, over the map
  algorithms::BoardUpdate board_update_{};
  algorithms::BoardFeatures observed_{};
  std::uint64_t observations_ = 0;  ///< board_observations()
  algorithms::BoardAssessment assessment_{};
  algorithms::HarmonicFix robust_fix_{};
  algorithms::FixBoardCheck fix_check_;
  /// This frame's centroid-column features (the map's feature order), when the frame's columns
  /// were measured.
  algorithms::ColumnFeatures columns_{};
  bool columns_valid_ = false;
  // The features this frame's fixes compare: not the boards its side cuts (uncut_features()).
  algorithms::FeatureMask uncut_{};
  const algorithms::ColumnFeatures* frame_columns() const {
    return columns_valid_ ? &columns_ : nullptr;
  }
  algorithms::FixCheckParams fix_check_params_;  ///< from the map's calibration (or none)
  algorithms::KidnapDetector kidnap_;
  /// The kidnap test's parameters with the scene-dependent ones derived from the map.
  algorithms::KidnapParams kidnap_params_;
  algorithms::DiffDriveGeometry geometry_;  // effective_geometry()
  /// The boards' model with the scene-dependent parts taken from the map's calibration.
  algorithms::BoardModelParams board_params_;
  /// Width of the harmonic fix's term in the per-board update (0: none; maps before version 4).
  double fix_term_sigma_m_ = 0.0;
  /// The map's per-sample fix errors over the forward map's cells (empty without them).
  algorithms::FixErrorGrid fix_errors_;
  /// Spread of the particles around a fix at start-up and at a kidnap's re-seed (metres).
  double init_sigma_m_ = 0.05;
  double reseed_sigma_m_ = 0.04;
  /// On a floor map with bearings (route terms off, kidnap.floor_search): the search over the
  /// whole floor that gives the kidnap test its evidence in place of the harmonic fix, whose
  /// error on a floor is tens of centimetres. It scans a slice of the grid each cycle; the best
  /// pose of its last pass (or the one followed since, if that fits better) is refined on each
  /// frame.
  static constexpr std::size_t kFloorPassPlaces = 3072;
  static constexpr std::size_t kFloorPlacesPerCycle = 256;
  /// The refinements' levels: steps of half a stride, then a quarter and an eighth (3, 1.5 and
  /// 0.75 cm at a 3-cell stride of 2 cm cells; 41 places, against 25 at one level): a board's
  /// area changes by its trained width over a centimetre or two, finer than a pass's places.
  static constexpr int kFloorRefineLevels = 3;
  /// The search and its comparison with the estimate leave no board out: after a kidnap the
  /// boards the robot now sees are the ones the motion index writes off
  /// (localization_cycle_update.cpp).
  static constexpr std::uint32_t kFloorSearchLeaveOut = 0U;
  bool floor_search_on_ = false;
  std::uint32_t floor_stride_ = 1;  ///< cells between the places a pass tries, along each axis
  double floor_refine_m_ = 0.02;    ///< the refinement's reach: a stride
  double floor_margin_nats_ = 0.0;  ///< the luck of a pass's best over the estimate's (nats)
  algorithms::FloorSearch floor_search_;
  algorithms::FloorPose floor_fix_{};
  // On a floor map with bearings: a seed's heading from the boards' bearings (observed_), and
  // the frames the first seed has let pass for want of one (at most kStartWaitFrames).
  bool seed_heading_from_boards_ = false;
  static constexpr std::uint32_t kStartWaitFrames = 30;
  std::uint32_t start_waits_ = 0;
  /// filter.seed_from_search on a floor map with the floor search: the first seed waits (within
  /// kStartWaitFrames) for the search's first pass and starts on its pose and the fix.
  bool start_from_search_ = false;
  // On a floor map: the sequential test between the estimate and the best pose near it.
  bool nearby_on_ = false;
  algorithms::NearbyPoseTest nearby_;
  /// Frames left in which the nearby pose test may take the floor search's pose (after a
  /// re-seed, for as many frames as it tests an alternative).
  std::uint32_t nearby_hint_frames_ = 0;
  algorithms::KidnapVerdict kidnap_verdict_ = algorithms::KidnapVerdict::kNone;
  algorithms::KidnapInput kidnap_input_{};
  const char* pending_text_ = nullptr;  ///< a STATUSTEXT this cycle's publish sends
  /// The overrun alarm's STATUSTEXT, raised or cleared at the end of the previous cycle.
  const char* pending_overrun_text_ = nullptr;
  bool overrun_alarm_enabled_ = false;
  bool overrun_alarm_ = false;
  std::uint32_t overrun_streak_ = 0;  ///< overruns in a row (alarm off) or cycles within (on)
  mavlink::Encoder mavlink_;
  mavlink::Signer signer_;
  hal::PersistentRecord* signing_store_ = nullptr;
  std::array<char, hal::PersistentRecord::kMaxBytes> signing_record_{};
  mavlink::CommandReceiver receiver_;
  const bool use_boards_;
  // The route term and the route heading term (RouteTerms): off for a floor map by default.
  bool route_terms_ = true;
  mavlink::FrameBuffer frame_buffer_{};
  std::array<LatencyHistogram, kStageCount> histograms_{};
  LatencyHistogram capture_to_send_{};
  LatencyWindow capture_to_send_window_{};  ///< this heartbeat period's, for the link
  bool frame_this_cycle_ = false;  ///< a new frame was taken this cycle (at frame_time_ns_)
  std::uint64_t frame_time_ns_ = 0;

  std::uint64_t period_ns_;
  std::uint64_t budget_ns_;
  std::uint64_t data_time_ns_ = 0;
  bool have_data_time_ = false;
  std::uint64_t last_frame_ns_ = 0;  ///< timestamp of the last frame used
  bool have_frame_time_ = false;
  bool live_clock_ = false;
  std::uint64_t last_fix_ns_ = 0;  ///< the last frame that counted as vision
  /// The cloud's position spread reached filter.nominal_spread_m and has not yet come back under
  /// filter.nominal_resume_spread_m: not nominal (HealthCause::kSpreadWide).
  bool spread_wide_ = false;
  bool ever_fix_ = false;
  /// The last frame that would have counted as vision had the map covered the estimate's
  /// heading at its place (the same as last_fix_ns_ wherever it does).
  std::uint64_t last_view_ns_ = 0;
  /// The last frame whose boards were weighed and disagreed with the estimate, with no fix the
  /// filter weighs to vouch for it (update_with_boards).
  std::uint64_t last_disagree_ns_ = 0;
  algorithms::HarmonicFix last_known_fix_{};  ///< the latest fix of a known place
  std::uint64_t last_encoder_ns_ = 0;
  bool have_encoder_ = false;
  /// An encoder gap in progress: the cloud diffused since the last sample (vision only), and
  /// whether it was re-seeded meanwhile.
  enum class EncoderGap : std::uint8_t { kNone, kDiffused, kReseeded };
  EncoderGap gap_ = EncoderGap::kNone;
  algorithms::Pose2 gap_anchor_{};  ///< the estimate at the latest encoder sample
  bool have_anchor_ = false;
  algorithms::OdometryDelta gap_travel_{};
  hal::EncoderCounts last_counts_{};
  std::uint64_t next_heartbeat_ns_ = 0;
  std::uint8_t reset_counter_ = 0;
  Health last_reported_health_ = Health::kNotInitialized;
  HealthCause last_reported_cause_ = HealthCause::kInputs;
  /// The mapped region with its margin (map frame): where a published pose may be nominal.
  double region_min_x_m_ = 0.0, region_max_x_m_ = 0.0;
  double region_min_y_m_ = 0.0, region_max_y_m_ = 0.0;
  bool heartbeat_requested_ = false;  ///< a peer asked for one: sent this cycle, off schedule
  /// The re-seed of the filter the commands of this cycle ask for. Each replaces the whole
  /// cloud, so only the last is carried out: a burst of commands costs one re-seed.
  struct Reseed {
    enum class Kind : std::uint8_t { kNone, kAround, kOverMap } kind = Kind::kNone;
    algorithms::Pose2 centre{};
    double position_sigma_m = 0.0;
    double yaw_sigma_rad = 0.0;
    bool uniform_yaw = false;
  };
  Reseed reseed_{};

  PoseOutput pose_{};
  FixOutput fix_{};
  CycleCounters counters_{};
};

}  // namespace harmoloc::firmware
