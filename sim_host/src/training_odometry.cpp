#include "harmoloc/sim_host/training_odometry.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "harmoloc/dataset/candump_log.hpp"

namespace harmoloc::sim_host {

namespace fs = std::filesystem;

std::vector<algorithms::OdometrySample> OdometryTrack::relative_to(std::uint64_t t0_ns) const {
  std::vector<algorithms::OdometrySample> out;
  out.reserve(timestamp_ns.size());
  for (std::size_t i = 0; i < timestamp_ns.size(); ++i) {
    const double t = timestamp_ns[i] >= t0_ns
                         ? static_cast<double>(timestamp_ns[i] - t0_ns) * 1e-9
                         : -static_cast<double>(t0_ns - timestamp_ns[i]) * 1e-9;
    out.push_back(algorithms::OdometrySample{t, left_ticks[i], right_ticks[i]});
  }
  return out;
}

namespace {

void append(OdometryTrack& track, std::uint64_t t_ns, std::uint32_t left, std::uint32_t right,
            std::uint8_t bits, std::uint32_t& last_left, std::uint32_t& last_right) {
  if (!track.timestamp_ns.empty() && t_ns <= track.timestamp_ns.back()) return;
  if (track.timestamp_ns.empty()) {
    track.left_ticks.push_back(0);
    track.right_ticks.push_back(0);
  } else {
    track.left_ticks.push_back(track.left_ticks.back() +
                               algorithms::wrapped_delta(last_left, left, bits));
    track.right_ticks.push_back(track.right_ticks.back() +
                                algorithms::wrapped_delta(last_right, right, bits));
  }
  track.timestamp_ns.push_back(t_ns);
  last_left = left;
  last_right = right;
}

}  // namespace

OdometryTrack odometry_from_can(const std::vector<algorithms::CanFrame>& frames,
                                const algorithms::EncoderFrameLayout& layout,
                                const algorithms::DiffDriveGeometry& geometry) {
  OdometryTrack track;
  track.geometry = geometry;
  std::uint32_t last_left = 0, last_right = 0;
  for (const algorithms::CanFrame& f : frames) {
    std::uint32_t left = 0, right = 0;
    if (algorithms::decode_encoder_frame(layout, f, left, right) != algorithms::CanDecode::kOk)
      continue;
    append(track, f.timestamp_ns, left, right, layout.counter_bits, last_left, last_right);
  }
  return track;
}

OdometryTrack odometry_from_gpio(const std::vector<dataset::EncoderSample>& samples,
                                 std::uint8_t counter_bits,
                                 const algorithms::DiffDriveGeometry& geometry) {
  OdometryTrack track;
  track.geometry = geometry;
  std::uint32_t last_left = 0, last_right = 0;
  for (const dataset::EncoderSample& s : samples)
    append(track, s.timestamp_ns, s.left_ticks, s.right_ticks, counter_bits, last_left, last_right);
  return track;
}

OdometryTrack read_dataset_odometry(const std::string& dataset_dir,
                                    const dataset::DatasetMetadata& meta) {
  const std::string path = (fs::path(dataset_dir) / meta.encoder_log).string();
  if (meta.encoder_source == dataset::EncoderSource::kGpio)
    return odometry_from_gpio(dataset::read_encoder_csv(path, meta.encoder_layout.counter_bits),
                              meta.encoder_layout.counter_bits, meta.geometry);
  return odometry_from_can(dataset::read_candump_log(path), meta.encoder_layout, meta.geometry);
}

OdometryTrack read_odometry_file(const std::string& path,
                                 const algorithms::EncoderFrameLayout& layout,
                                 const algorithms::DiffDriveGeometry& geometry) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::string first;
  std::getline(in, first);
  if (!first.empty() && first.back() == '\r') first.pop_back();
  if (first == dataset::kEncoderCsvHeader)
    return odometry_from_gpio(dataset::read_encoder_csv(path, layout.counter_bits),
                              layout.counter_bits, geometry);
  return odometry_from_can(dataset::read_candump_log(path), layout, geometry);
}

}  // namespace harmoloc::sim_host
