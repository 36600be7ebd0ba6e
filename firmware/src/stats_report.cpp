#include "harmoloc/firmware/stats_report.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

namespace harmoloc::firmware {

namespace {

double us(std::uint64_t ns) {
  return static_cast<double>(ns) / 1000.0;
}

}  // namespace

std::string stats_json(const LocalizationCycle& cycle, const RunCounters& run) {
  const CycleCounters& c = cycle.counters();
  std::ostringstream o;
  o.precision(6);
  o << "{\n  \"harmoloc_version\": \"" << HARMOLOC_VERSION << "\",\n"
    << "  \"board\": \"" << run.board << "\",\n"
    << "  \"ended\": \"" << run.ended << "\",\n"
    << "  \"outputs_failed\": " << run.outputs_failed << ",\n"
    << "  \"rate_hz\": " << run.rate_hz << ",\n"
    << "  \"budget_us\": " << us(cycle.budget_ns()) << ",\n"
    << "  \"cycles\": " << c.cycles << ",\n"
    << "  \"frames\": " << c.frames << ",\n"
    << "  \"overruns\": " << c.overruns << ",\n"
    << "  \"pacing\": {\"mode\": \"" << run.pacing << "\", \"skipped_ticks\": " << run.skipped_ticks
    << ", \"overrun_alarms\": " << c.overrun_alarms << "},\n"
    << "  \"stages\": {";
  for (std::size_t s = 0; s < kStageCount; ++s) {
    const LatencyHistogram& h = cycle.stage_histogram(static_cast<Stage>(s));
    o << (s == 0 ? "\n" : ",\n") << "    \"" << stage_name(static_cast<Stage>(s))
      << "\": {\"median_us\": " << us(h.quantile_ns(0.5))
      << ", \"p99_us\": " << us(h.quantile_ns(0.99))
      << ", \"p999_us\": " << us(h.quantile_ns(0.999)) << ", \"max_us\": " << us(h.max_ns())
      << ", \"mean_us\": " << h.mean_ns() / 1000.0 << "}";
  }
  o << "\n  },\n  \"cycle_histogram\": {\"upper_us\": [";
  const LatencyHistogram& whole = cycle.stage_histogram(Stage::kCycle);
  std::ostringstream counts;
  bool first = true;
  for (std::size_t i = 0; i < LatencyHistogram::kBuckets; ++i) {
    if (whole.bucket_count(i) == 0) continue;
    o << (first ? "" : ", ") << us(LatencyHistogram::bucket_upper_ns(i));
    counts << (first ? "" : ", ") << whole.bucket_count(i);
    first = false;
  }
  o << "], \"counts\": [" << counts.str() << "]},\n"
    << "  \"health_cycles\": {\"not_initialized\": " << c.cycles_in_health[0]
    << ", \"nominal\": " << c.cycles_in_health[1]
    << ", \"odometry_only\": " << c.cycles_in_health[2]
    << ", \"vision_only\": " << c.cycles_in_health[3] << ", \"invalid\": " << c.cycles_in_health[4]
    << "},\n"
    << "  \"degraded\": {\"odometry_only\": " << c.cycles_in_health[2]
    << ", \"vision_only\": " << c.cycles_in_health[3] << ", \"invalid\": " << c.cycles_in_health[4]
    << "},\n"
    << "  \"camera\": {\"frames\": " << run.camera.frames << ", \"corrupt\": " << run.camera.corrupt
    << ", \"dropped\": " << run.camera.dropped << ", \"errors\": " << run.camera.errors
    << ", \"reopens\": " << run.camera.reopens << ", \"no_frame_cycles\": " << c.no_frame
    << ", \"size_mismatch\": " << c.frame_size_mismatch << ", \"stale\": " << c.stale_frames
    << "},\n"
    << "  \"encoders\": {\"samples\": " << run.encoders.samples
    << ", \"gaps_bridged\": " << c.encoder_gaps_bridged
    << ", \"ignored_id\": " << run.encoders.ignored_id
    << ", \"bad_length\": " << run.encoders.bad_length
    << ", \"glitches\": " << run.encoders.glitches
    << ", \"bus_errors\": " << run.encoders.bus_errors << ", \"bus_off\": " << run.encoders.bus_off
    << ", \"overflows\": " << run.encoders.overflows << "},\n"
    << "  \"link\": {\"frames_sent\": " << run.link.frames_sent
    << ", \"frames_dropped\": " << run.link.frames_dropped
    << ", \"bytes_sent\": " << run.link.bytes_sent << ", \"errors\": " << run.link.errors << "},\n"
    << "  \"localizer\": {\"fixes\": " << c.fixes_used << ", \"unknown_place\": " << c.unknown_place
    << ", \"implausible_frames\": " << c.implausible_frames
    << ", \"off_map_cycles\": " << c.off_map_cycles << "},\n"
    << "  \"filter\": {\"observation\": \"" << (cycle.uses_boards() ? "boards" : "fix")
    << "\", \"resamples\": " << c.resamples << ", \"no_consensus\": " << c.no_consensus
    << ", \"distrusted_board_frames\": " << c.distrusted_boards
    << ", \"fix_board_suspicions\": " << c.fix_board_suspicions
    << ", \"kidnap_triggers\": " << c.kidnap_triggers << ", \"kidnaps\": " << c.kidnaps
    << ", \"lost\": " << c.lost << "}";
  const mavlink::InboundCounters in = cycle.inbound_counters();
  o << ",\n  \"inbound\": {\"bytes_in\": " << in.bytes_in << ", \"frames_in\": " << in.frames_in
    << ", \"crc_errors\": " << in.crc_errors << ", \"bad_headers\": " << in.bad_headers
    << ", \"garbage_bytes\": " << in.garbage_bytes
    << ", \"commands_accepted\": " << in.commands_accepted
    << ", \"commands_refused\": " << in.commands_refused
    << ", \"rejected_unsigned\": " << in.rejected_unsigned
    << ", \"rejected_bad_signature\": " << in.rejected_bad_signature
    << ", \"rejected_replay\": " << in.rejected_replay
    << ", \"rejected_future\": " << in.rejected_future
    << ", \"rejected_source\": " << in.rejected_source
    << ", \"ignored_messages\": " << in.ignored_messages
    << ", \"timesync_requests\": " << in.timesync_requests
    << ", \"saturated_cycles\": " << in.saturated_cycles << "}";
  const auto latency = [&o](const char* name, const LatencyHistogram& h) {
    o << ",\n  \"" << name << "\": {\"count\": " << h.count() << ", \"min_us\": " << us(h.min_ns())
      << ", \"mean_us\": " << h.mean_ns() / 1000.0 << ", \"median_us\": " << us(h.quantile_ns(0.5))
      << ", \"p99_us\": " << us(h.quantile_ns(0.99))
      << ", \"p999_us\": " << us(h.quantile_ns(0.999)) << ", \"max_us\": " << us(h.max_ns()) << "}";
  };
  if (run.wakeup_latency != nullptr && run.wakeup_latency->count() > 0)
    latency("wakeup_latency", *run.wakeup_latency);
  if (cycle.capture_to_send().count() > 0) latency("capture_to_send", cycle.capture_to_send());
  if (run.recording.active) {
    o << ",\n  \"recording\": {\"frames\": " << run.recording.frames
      << ", \"dropped\": " << run.recording.dropped << ", \"skipped\": " << run.recording.skipped
      << ", \"bytes\": " << run.recording.bytes << ", \"stopped\": \"" << run.recording.stopped
      << "\"}";
  }
  if (run.rss_kb_end >= 0) {
    o << ",\n  \"resources\": {\"rss_kb_start\": " << run.rss_kb_start
      << ", \"rss_kb_end\": " << run.rss_kb_end << ", \"peak_rss_kb\": " << run.peak_rss_kb
      << ", \"open_fds_start\": " << run.open_fds_start
      << ", \"open_fds_end\": " << run.open_fds_end << "}";
  }
  o << "\n}\n";
  return o.str();
}

std::string write_stats(const std::string& path, const std::string& json) {
  errno = 0;
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return path + ": cannot write (" + std::strerror(errno) + ")";
  const bool wrote = std::fwrite(json.data(), 1, json.size(), f) == json.size();
  int error = wrote ? 0 : errno;
  if (std::fclose(f) != 0 && error == 0) error = errno;
  if (!wrote || error != 0)
    return path + ": write failed (" + std::strerror(error != 0 ? error : EIO) + ")";
  return {};
}

}  // namespace harmoloc::firmware
