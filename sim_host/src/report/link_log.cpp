#include "harmoloc/sim_host/link_log.hpp"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <system_error>

#include "harmoloc/firmware/mavlink_parser.hpp"
#include "harmoloc/firmware/pose_messages.hpp"
#include "harmoloc/sim_host/report_error.hpp"

namespace harmoloc::sim_host {

namespace mv = firmware::mavlink;
using firmware::Health;

namespace {

/// Builds the health spans as the poses come: changes seen since the last pose wait in
/// pending_ until the next pose says when they took effect.
class HealthTimeline {
 public:
  void heartbeat(std::uint8_t system_status) {
    // Only the state before anything else is known: later, STATUSTEXT says exactly.
    Health h{};
    if (!seen_text_ && spans_.empty() && firmware::health_of_heartbeat(system_status, h)) {
      current_ = h;
    }
  }
  void text(Health h) {
    seen_text_ = true;
    pending_.push_back(h);
  }
  Health pose(double t_s) {
    if (spans_.empty()) {
      if (!pending_.empty()) current_ = pending_.back();
      pending_.clear();
      spans_.push_back({t_s, t_s, current_});
      return current_;
    }
    HealthSpan& open = spans_.back();
    if (!pending_.empty()) {
      // All but the last change share the gap since the previous pose; the last holds from now.
      const double gap_start_s = open.end_s;
      const std::size_t between = pending_.size() - 1;
      const double share_s =
          (t_s - gap_start_s) / static_cast<double>(std::max<std::size_t>(between, 1));
      for (std::size_t i = 0; i < between; ++i) {
        push(gap_start_s + share_s * static_cast<double>(i),
             gap_start_s + share_s * static_cast<double>(i + 1), pending_[i]);
      }
      push(t_s, t_s, pending_.back());
      pending_.clear();
    }
    spans_.back().end_s = t_s;
    return spans_.back().health;
  }
  std::vector<HealthSpan> take() { return std::move(spans_); }

 private:
  void push(double start_s, double end_s, Health h) {
    HealthSpan& last = spans_.back();
    if (last.end_s < start_s) last.end_s = start_s;
    if (last.health == h) {
      last.end_s = std::max(last.end_s, end_s);
      return;
    }
    spans_.push_back({start_s, end_s, h});
  }

  Health current_ = Health::kNotInitialized;
  bool seen_text_ = false;
  std::vector<Health> pending_;
  std::vector<HealthSpan> spans_;
};

}  // namespace

LinkLog parse_link_log(const std::vector<std::uint8_t>& bytes) {
  LinkLog log;
  HealthTimeline timeline;
  mv::FrameParser parser;
  mv::RxFrame frame;
  std::size_t fed = 0;
  for (;;) {
    std::size_t room = 0;
    std::uint8_t* to = parser.write_area(room);
    const std::size_t n = std::min(room, bytes.size() - fed);
    if (n > 0) std::memcpy(to, bytes.data() + fed, n);
    parser.commit(n);
    fed += n;
    std::size_t work = static_cast<std::size_t>(-1);
    bool any = false;
    while (parser.next(frame, work)) {
      any = true;
      switch (frame.msg_id) {
        case mv::kMsgOdometry: {
          const firmware::MapPose m =
              firmware::map_pose(firmware::decode_odometry(frame.payload.data()));
          LinkPose p;
          p.t_s = m.t_s;
          p.pose = algorithms::Pose2{m.x_m, m.y_m, m.yaw_rad};
          p.sigma_m = m.sigma_m;
          p.quality = m.quality;
          p.health = timeline.pose(m.t_s);
          log.poses.push_back(p);
          break;
        }
        case mv::kMsgHeartbeat:
          timeline.heartbeat(frame.payload[7]);  // custom_mode(4) type autopilot base_mode status
          break;
        case mv::kMsgStatustext: {
          Health h{};
          const char* text = reinterpret_cast<const char*>(frame.payload.data() + 1);
          if (firmware::health_of_text(text, 50, h)) {
            ++log.health_texts;
            timeline.text(h);
          }
          break;
        }
        default:
          break;
      }
    }
    if (n == 0 && !any) {
      // Nothing new fitted and nothing decoded: the front is an unfinished frame or a false
      // start; give it up a byte at a time (the parser's own remedy for a quiet line).
      if (!parser.skip_candidate()) break;
    }
  }
  log.frames = parser.counters().frames;
  log.crc_errors = parser.counters().crc_errors;
  log.health = timeline.take();
  return log;
}

LinkLog read_link_log(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw ReportError(path + ": is a directory, expected a link file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ReportError(path + ": cannot open the link file");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  LinkLog log = parse_link_log(bytes);
  if (log.poses.empty()) {
    throw ReportError(path + ": no ODOMETRY in the link file (is it `harmoloc --link FILE`?)");
  }
  return log;
}

}  // namespace harmoloc::sim_host
