// harmoloc-monitor: what harmoloc says on its link, read as a person or a script wants it. Reads
// the MAVLink stream from a serial device, a pty or a recorded link file (harmoloc --link FILE),
// decodes it with the firmware's own parser and prints the pose in the map frame (as the TUM
// files have it), its spread and quality, the health, the last STATUSTEXT, message rates and
// link errors; sends the three commands (relocalize, set pose, request a message), signed when
// given the link's key. Runs on the laptop or on the robot.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harmoloc/dataset/tum.hpp"
#include "harmoloc/drivers/serial_link.hpp"
#include "harmoloc/drivers/stop_signals.hpp"
#include "harmoloc/firmware/cli.hpp"
#include "harmoloc/firmware/config.hpp"
#include "harmoloc/firmware/mavlink_inbound.hpp"
#include "harmoloc/firmware/mavlink_parser.hpp"
#include "harmoloc/firmware/mavlink_signing.hpp"
#include "harmoloc/firmware/mavlink_v2.hpp"
#include "harmoloc/firmware/pose_messages.hpp"
#include "monitor_parts.hpp"

using namespace monitor_detail;

namespace {

using namespace harmoloc;
namespace mv = firmware::mavlink;

int fail(const std::string& why) {
  std::fprintf(stderr, "harmoloc-monitor: %s\n", why.c_str());
  return 2;
}

std::uint64_t monotonic_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::steady_clock::now().time_since_epoch())
                                        .count());
}

// Where the bytes come from: a file or FIFO read to its end, or a device (serial line, pty)
// read without blocking, which commands can also be sent to.
class Source {
 public:
  std::string open(const std::string& path, unsigned baud) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return path + ": " + std::strerror(errno);
    if (S_ISDIR(st.st_mode)) return path + ": is a directory, not a link file or device";
    if (S_ISCHR(st.st_mode)) {
      device_ = true;
      const std::string e = link_.open(path, baud);
      if (!e.empty()) return path + ": " + e;
      if (!link_.can_receive()) return path + ": cannot be read (not a terminal)";
      return "";
    }
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) return path + ": " + std::strerror(errno);
    return "";
  }
  bool device() const { return device_; }
  /// Bytes read into @p dst (0: none now); false at the end of a file or on an error.
  bool read(std::uint8_t* dst, std::size_t max, std::size_t& got) {
    got = 0;
    if (device_) {
      got = link_.read_bytes(dst, max);
      return true;
    }
    const ssize_t n = ::read(fd_, dst, max);
    if (n < 0 && errno == EINTR) return true;
    if (n <= 0) return false;
    got = static_cast<std::size_t>(n);
    return true;
  }
  bool send(const std::uint8_t* bytes, std::size_t size) {
    return device_ && link_.write_frame(bytes, size) == hal::LinkWrite::kSent;
  }
  ~Source() {
    if (fd_ >= 0) ::close(fd_);
  }

 private:
  drivers::SerialLink link_;
  int fd_ = -1;
  bool device_ = false;
};

struct Command {
  std::uint16_t id = 0;
  std::array<float, 7> params{};
  bool acked = false;
};

// X,Y,YAW[,SIGMA_M[,YAW_SIGMA_RAD]] in the map frame -> the command's parameters.
bool parse_pose(const std::string& text, std::array<float, 7>& params) {
  double v[5] = {0, 0, 0, 0, 0};
  char extra = 0;
  const int n =
      std::sscanf(text.c_str(), "%lf,%lf,%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &v[3], &v[4], &extra);
  if (n < 3 || n > 5) return false;
  for (const double x : v)
    if (!std::isfinite(x) || std::fabs(x) > 1e4) return false;
  // The command takes LOCAL_FRD, as ODOMETRY reports it: y and yaw mirrored; 0 spreads leave
  // the firmware's defaults.
  params = {static_cast<float>(v[0]),
            static_cast<float>(-v[1]),
            static_cast<float>(-v[2]),
            static_cast<float>(v[3]),
            static_cast<float>(v[4]),
            0,
            0};
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "harmoloc-monitor: reads harmoloc's MAVLink stream from a serial device, a pty or a\n"
      "recorded link file (harmoloc --link FILE) and shows the pose in the map frame (as the TUM\n"
      "files), its spread and quality, the health, the last STATUSTEXT, message rates, link\n"
      "errors and the capture-to-send latency: a live view on a terminal, one JSON line per\n"
      "ODOMETRY with --json, TUM with --tum.\n"
      "With a device it can send the commands (relocalize, set pose, request), signed with --key.\n"
      "A file is read to its end; a device until Ctrl-C, --duration or --count.",
      "harmoloc-monitor"};
  std::string source_path, tum_path, key_path, set_pose;
  bool json = false, relocalize = false;
  unsigned baud = 115200;
  double duration_s = 0.0;
  std::uint64_t count = 0;
  int request = -1;
  unsigned sysid = 255, compid = 190, target_system = 1, target_component = 197;
  app.add_option("SOURCE", source_path, "serial device, pty or recorded link file")->required();
  app.add_flag("--json", json,
               "one JSON object per ODOMETRY on stdout: t (s), x, y (m), yaw (rad) in the map\n"
               "frame, sigma_m, quality, reset_counter, health; capture_to_send_ms (the last\n"
               "second's median, live boards) once the link has said it");
  app.add_option("--tum", tum_path, "write every ODOMETRY's pose here (TUM, map frame)");
  app.add_option("--baud", baud, "baud of a serial device (as the firmware's link.baud)")
      ->check(CLI::Range(50U, 4000000U));
  app.add_option("--key", key_path,
                 "the link's signing key file (32 bytes or 64 hex digits): commands are signed\n"
                 "with it and the frames' signatures checked");
  app.add_flag("--relocalize", relocalize, "send \"relocalize now\" (device only)");
  app.add_option("--set-pose", set_pose,
                 "send \"set pose\" X,Y,YAW[,SIGMA_M[,YAW_SIGMA_RAD]] in the map frame (m, m,\n"
                 "rad; the spreads default to the firmware's; device only)");
  app.add_option("--request", request,
                 "send \"request message\" for this id (0 HEARTBEAT, 331 ODOMETRY)")
      ->check(CLI::Range(0, 16777215));
  app.add_option("--sysid", sysid, "our system id (the firmware accepts link.accept_system_ids)")
      ->check(CLI::Range(1U, 255U));
  app.add_option("--compid", compid, "our component id (link.accept_component_ids)")
      ->check(CLI::Range(0U, 255U));
  app.add_option("--target-system", target_system, "harmoloc's system id (link.system_id)")
      ->check(CLI::Range(1U, 255U));
  app.add_option("--target-component", target_component,
                 "harmoloc's component id (link.component_id)")
      ->check(CLI::Range(0U, 255U));
  app.add_option("--duration", duration_s, "stop after this many seconds (device; 0: never)")
      ->check(CLI::Range(0.0, 1e7));
  app.add_option("--count", count, "stop after this many ODOMETRY messages (0: never)");
  if (const auto status = harmoloc::cli::parse(app, argc, argv)) return *status;

  std::vector<Command> commands;
  if (relocalize) commands.push_back(Command{mv::kCmdRelocalize, {}, false});
  if (!set_pose.empty()) {
    Command c{mv::kCmdSetPose, {}, false};
    if (!parse_pose(set_pose, c.params))
      return fail("--set-pose wants X,Y,YAW[,SIGMA_M[,YAW_SIGMA_RAD]] (finite numbers), got \"" +
                  set_pose + "\"");
    commands.push_back(c);
  }
  if (request >= 0)
    commands.push_back(Command{mv::kCmdRequestMessage, {static_cast<float>(request)}, false});

  mv::SigningKey key{};
  const bool keyed = !key_path.empty();
  if (keyed) {
    if (const std::string e = firmware::read_signing_key_file(key_path, key); !e.empty())
      return fail(key_path + ": " + e);
  }
  Source source;
  if (const std::string e = source.open(source_path, baud); !e.empty()) return fail(e);
  if (!commands.empty() && !source.device())
    return fail("commands need a serial device or pty, not a file: " + source_path);
  std::FILE* tum = nullptr;
  if (!tum_path.empty()) {
    tum = std::fopen(tum_path.c_str(), "w");
    if (tum == nullptr) return fail(tum_path + ": cannot write (" + std::strerror(errno) + ")");
  }

  // Outbound: our own frames, signed on the wall clock as the firmware's are.
  mv::Signer signer;
  mv::Encoder encoder(static_cast<std::uint8_t>(sysid), static_cast<std::uint8_t>(compid));
  // Inbound signature check: the firmware's clock may differ from ours; take its time from its
  // first frame.
  mv::Signer checker;
  if (keyed) {
    signer.configure(key, 0);
    const auto wall_us =
        static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                       std::chrono::system_clock::now().time_since_epoch())
                                       .count());
    signer.set_time(mv::signing_timestamp_from_unix_us(wall_us), monotonic_ns());
    encoder.set_signer(&signer);
    mv::SigningOptions peer;
    peer.peer_clock = true;
    checker.configure(key, 0, peer);
  }
  mv::FrameBuffer buffer{};
  for (const Command& c : commands) {
    signer.advance(monotonic_ns());
    const std::size_t n =
        encoder.command_long(c.id, c.params, static_cast<std::uint8_t>(target_system),
                             static_cast<std::uint8_t>(target_component), buffer);
    if (!source.send(buffer.data(), n)) return fail(source_path + ": could not send the command");
    std::fprintf(stderr, "harmoloc-monitor: sent %s%s\n", command_name(c.id),
                 keyed ? " (signed)" : "");
  }

  drivers::install_stop_signals();
  const bool live_view = !json && source.device() && ::isatty(STDOUT_FILENO) != 0;
  mv::FrameParser parser;
  mv::RxFrame frame;
  View view;
  const std::uint64_t start_ns = monotonic_ns();
  std::uint64_t next_draw_ns = start_ns;
  bool ended = false;
  int status = 0;
  while (!ended) {
    if (drivers::stop_signal() != 0) break;
    std::size_t room = 0;
    std::uint8_t* to = parser.write_area(room);
    std::size_t got = 0;
    if (!source.read(to, room, got)) ended = true;
    parser.commit(got);
    std::size_t work = static_cast<std::size_t>(-1);
    while (parser.next(frame, work)) {
      ++view.frames;
      if (keyed) {
        switch (checker.verify(frame.bytes, frame.size)) {
          case mv::SignatureCheck::kAccepted:
            ++view.signed_ok;
            break;
          case mv::SignatureCheck::kUnsigned:
            ++view.unsigned_frames;
            break;
          default:
            ++view.signed_bad;
            break;
        }
      } else if (!frame.is_signed()) {
        ++view.unsigned_frames;
      }
      switch (frame.msg_id) {
        case mv::kMsgOdometry: {
          const firmware::MapPose m =
              firmware::map_pose(firmware::decode_odometry(frame.payload.data()));
          if (view.odometry++ == 0) view.first_t_s = m.t_s;
          view.pose = m;
          if (json) {
            nlohmann::ordered_json j;
            j["t"] = m.t_s;
            j["x"] = m.x_m;
            j["y"] = m.y_m;
            j["yaw"] = m.yaw_rad;
            j["sigma_m"] = m.sigma_m;
            j["quality"] = m.quality;
            j["reset_counter"] = m.reset_counter;
            j["health"] = m.quality < 0 ? std::string("invalid") : health_text_of(view);
            if (view.latency_p50_ms) j["capture_to_send_ms"] = *view.latency_p50_ms;
            std::printf("%s\n", j.dump().c_str());
          }
          if (tum != nullptr) {
            char line[160];
            const int n = dataset::format_tum_line(line, sizeof line, m.t_s,
                                                   algorithms::Pose2{m.x_m, m.y_m, m.yaw_rad});
            if (n > 0) std::fwrite(line, 1, static_cast<std::size_t>(n), tum);
          }
          break;
        }
        case mv::kMsgHeartbeat:
          ++view.heartbeats;
          view.heartbeat_status = frame.payload[7];  // custom_mode(4) type autopilot base_mode
          if (!view.health) {
            firmware::Health h{};
            if (firmware::health_of_heartbeat(frame.payload[7], h)) view.health = h;
          }
          break;
        case mv::kMsgStatustext: {
          ++view.texts;
          const char* text = reinterpret_cast<const char*>(frame.payload.data() + 1);
          view.last_text.assign(text, ::strnlen(text, 50));
          firmware::Health h{};
          if (firmware::health_of_text(text, 50, h)) view.health = h;
          if (!json && !live_view) std::fprintf(stderr, "STATUSTEXT %s\n", view.last_text.c_str());
          break;
        }
        case mv::kMsgNamedValueFloat:
          ++view.other;
          take_named_value(frame, view);
          break;
        case mv::kMsgCommandAck: {
          ++view.acks;
          const std::uint16_t command =
              static_cast<std::uint16_t>(frame.payload[0] | (frame.payload[1] << 8U));
          const std::uint8_t result = frame.payload[2];
          if (frame.payload[8] != sysid || frame.payload[9] != compid) break;  // not ours
          for (Command& c : commands) {
            if (c.id != command || c.acked) continue;
            c.acked = true;
            std::fprintf(stderr, "harmoloc-monitor: %s: %s\n", command_name(command),
                         result_name(result));
            if (result != 0) status = 1;
            break;
          }
          break;
        }
        default:
          ++view.other;
          break;
      }
      if (count != 0 && view.odometry >= count) ended = true;
    }
    const std::uint64_t now = monotonic_ns();
    if (live_view && now >= next_draw_ns) {
      draw(view, parser.counters(), source_path, true);
      next_draw_ns = now + 250'000'000ULL;
    }
    if (duration_s > 0.0 && static_cast<double>(now - start_ns) * 1e-9 >= duration_s) break;
    if (source.device() && got == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (tum != nullptr && std::fclose(tum) != 0) {
    std::fprintf(stderr, "harmoloc-monitor: %s: write failed\n", tum_path.c_str());
    status = 1;
  }
  for (const Command& c : commands) {
    if (!c.acked) {
      std::fprintf(stderr, "harmoloc-monitor: %s: no COMMAND_ACK\n", command_name(c.id));
      status = 1;
    }
  }
  if (!json) draw(view, parser.counters(), source_path, false);
  return status;
}
