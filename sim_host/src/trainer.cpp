#include "harmoloc/sim_host/trainer.hpp"

#include <chrono>
#include <stdexcept>
#include <string>

#include "harmoloc/dataset/area_log.hpp"
#include "harmoloc/dataset/metadata.hpp"
#include "harmoloc/host/file_camera.hpp"
#include "trainer_parts.hpp"

namespace harmoloc::sim_host {

using trainer_detail::ms_since;

AreaSeries segment_dataset(const std::string& dataset_dir,
                           const algorithms::ThresholdSet& thresholds) {
  const dataset::DatasetMetadata meta = dataset::read_metadata(dataset_dir);
  host::FileCamera camera(dataset_dir, meta);
  std::vector<std::uint8_t> table_storage(algorithms::ColourTable::kEntries);
  algorithms::ColourTable table;
  table.build(algorithms::BoardClassifier(thresholds), table_storage.data());
  const auto t0 = std::chrono::steady_clock::now();
  AreaSeries run;
  run.image_width_px = meta.image_width_px;
  run.image_height_px = meta.image_height_px;
  run.areas.reserve(camera.frame_count());
  for (;;) {
    hal::FrameView frame;
    const hal::CameraStatus status = camera.acquire(frame, 0);
    if (status == hal::CameraStatus::kEnded) break;
    if (status != hal::CameraStatus::kFrame) continue;
    algorithms::AreaVector a;
    if (frame.format == hal::PixelFormat::kRgb24) {
      algorithms::segment_rgb24(frame.data, frame.width_px, frame.height_px, frame.stride_bytes,
                                table, a);
    } else {
      algorithms::segment_yuyv(frame.data, frame.width_px, frame.height_px, frame.stride_bytes,
                               table, a);
    }
    run.areas.push_back(a);
    run.timestamp_ns.push_back(frame.timestamp_ns);
    camera.release();
  }
  run.segment_ms = ms_since(t0);
  run.odometry = read_dataset_odometry(dataset_dir, meta);
  run.camera_forward_m = meta.camera_forward_m;
  run.camera_height_m = meta.camera_height_m;
  return run;
}

AreaSeries read_area_series(const std::string& areas_path,
                            const algorithms::ThresholdSet& thresholds) {
  const dataset::AreaLog log = dataset::read_area_log(areas_path);
  if (log.board_names.size() != thresholds.count) {
    throw std::runtime_error(areas_path + ": has " + std::to_string(log.board_names.size()) +
                             " boards but the config has " + std::to_string(thresholds.count));
  }
  if (log.thresholds_crc32 != dataset::thresholds_fingerprint(thresholds)) {
    throw std::runtime_error(areas_path +
                             ": was recorded with other colour thresholds than the config "
                             "(thresholds_crc32 differs); train with the config the robot used");
  }
  AreaSeries run;
  run.image_width_px = log.image_width_px;
  run.image_height_px = log.image_height_px;
  run.timestamp_ns = log.timestamp_ns;
  run.areas = log.areas;
  return run;
}

TrainReport train_map(const TrainOptions& opt, algorithms::MapFile& map) {
  if (opt.dataset_dir.empty() == opt.areas_path.empty())
    throw std::runtime_error("give either a dataset folder or an area log");
  AreaSeries run = opt.areas_path.empty() ? segment_dataset(opt.dataset_dir, opt.thresholds)
                                          : read_area_series(opt.areas_path, opt.thresholds);
  if (!opt.areas_path.empty() && !opt.encoders_path.empty())
    run.odometry = read_odometry_file(opt.encoders_path, opt.can_layout, opt.geometry);
  std::vector<dataset::StampedPose> labels = dataset::read_tum(opt.labels_path);
  if (labels.empty()) throw std::runtime_error(opt.labels_path + ": no labels");
  double offset_s = opt.label_offset_s;
  LabelOffsetEstimate estimate;
  if (opt.label_offset_auto) {
    if (run.odometry.empty() || !opt.use_odometry) {
      throw std::runtime_error(
          "--label-offset auto needs the run's wheel odometry (a dataset folder's encoder log, or "
          "--encoders with an area log)");
    }
    estimate = estimate_label_offset(run.odometry, labels);
    if (!estimate.found) {
      throw std::runtime_error("cannot estimate the labels' clock offset from the odometry: " +
                               estimate.why_not + "; give --label-offset SECONDS");
    }
    offset_s = estimate.offset_s;
  }
  for (dataset::StampedPose& l : labels) l.t_s += offset_s;
  TrainReport report = train_on_areas(run, labels, opt, map);
  report.label_offset_s = offset_s;
  report.label_offset_estimated = opt.label_offset_auto;
  report.label_offset = estimate;
  for (const dataset::StampedPose& l : labels)
    report.labels_have_yaw = report.labels_have_yaw || l.pose.yaw_rad != 0.0;
  check_trained_map(report, labels, map, opt);
  return report;
}

}  // namespace harmoloc::sim_host
