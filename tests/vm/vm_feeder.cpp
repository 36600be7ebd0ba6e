// Plays a simulated dataset (docs/dataset-format.md) into the kernel for the VM bench's whole-loop
// run: every frame written to a v4l2loopback output device (after VIDIOC_S_FMT: RGB24 for PPM
// frames, YUYV for raw ones) and every line of the candump log sent on a SocketCAN interface,
// both at their dataset times on one CLOCK_MONOTONIC schedule, slowed by one factor:
//   wall(t) = start + slowdown * (t - origin),  origin = the dataset's first event.
//
//   vm_feeder DATASET VIDEO_DEV CAN_IF SLOWDOWN [GO_FILE [EVENTS_CSV]]
//
// Before the clock starts it writes the first frame once (with exclusive_caps=1 the loopback
// offers a capture node only once a writer has set the format and written), then waits for
// GO_FILE to exist (the firmware is up). It prints, for the host:
//   FEEDER start_mono_ns=S origin_ns=O slowdown=K      when the clock starts
//   FEEDER done frames=N can=M frame_late_p50_ms=.. frame_late_max_ms=.. can_late_max_ms=..
//   frames_late_over_10ms=..
//          can_late_over_10ms=.. wall_s=..                  at the end
// and, with EVENTS_CSV, after the run, every event ("kind,t_ns,sent_mono_ns,done_mono_ns": f or
// c, its dataset time, when its write() began and when it returned; the kernel stamps a frame in
// between). When the VM cannot keep the schedule, the events go out late and in bursts;
// tests/vm/loop_clock.py maps between the clocks through them instead of the schedule, so a slow
// VM does not read as a wrong pose.
#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <linux/videodev2.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct FrameEntry {
  std::int64_t t_ns;
  std::string path;
};
struct CanEntry {
  std::int64_t t_ns;
  can_frame frame;
};

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "vm_feeder: %s\n", what.c_str());
  std::exit(2);
}

std::int64_t mono_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

void sleep_until(std::int64_t t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / 1000000000LL);
  ts.tv_nsec = static_cast<long>(t_ns % 1000000000LL);
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

std::vector<unsigned char> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) die("cannot open " + path);
  return std::vector<unsigned char>((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
}

// The pixel bytes of a frame file: PPM (P6, maxval 255) without its header, or raw YUYV as is.
struct Pixels {
  std::vector<unsigned char> bytes;
  std::size_t offset = 0;
  int width = 0, height = 0;
  bool rgb = false;
};
Pixels load_frame(const std::string& path, int meta_w, int meta_h) {
  Pixels p;
  p.bytes = read_file(path);
  if (p.bytes.size() > 2 && p.bytes[0] == 'P' && p.bytes[1] == '6') {
    // "P6" whitespace width whitespace height whitespace 255 one whitespace, then the pixels.
    std::size_t i = 2;
    int fields[3] = {0, 0, 0};
    for (int& f : fields) {
      while (i < p.bytes.size() && std::isspace(p.bytes[i])) ++i;
      while (i < p.bytes.size() && std::isdigit(p.bytes[i])) f = f * 10 + (p.bytes[i++] - '0');
    }
    p.offset = i + 1;
    p.width = fields[0];
    p.height = fields[1];
    p.rgb = true;
    if (fields[2] != 255 ||
        p.bytes.size() != p.offset + static_cast<std::size_t>(p.width) * p.height * 3)
      die(path + ": not an 8-bit P6 PPM of its stated size");
  } else {
    p.width = meta_w;
    p.height = meta_h;
    if (p.bytes.size() != static_cast<std::size_t>(meta_w) * meta_h * 2)
      die(path + ": a raw YUYV frame must be width x height x 2 bytes");
  }
  return p;
}

int meta_int(const std::string& metadata, const char* key) {
  std::istringstream in(metadata);
  std::string line;
  while (std::getline(in, line)) {
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    std::string k = line.substr(0, eq);
    k.erase(std::remove(k.begin(), k.end(), ' '), k.end());
    if (k == key) return std::atoi(line.c_str() + eq + 1);
  }
  return 0;
}

// "(1767225600.010000) can0 181#1A0000001C000000"
bool parse_candump(const std::string& line, CanEntry& out) {
  long long sec = 0, usec = 0;
  char iface[32], frame[64];
  if (std::sscanf(line.c_str(), " (%lld.%lld) %31s %63s", &sec, &usec, iface, frame) != 4)
    return false;
  const char* hash = std::strchr(frame, '#');
  if (hash == nullptr) return false;
  const std::size_t id_len = static_cast<std::size_t>(hash - frame);
  out = CanEntry{};
  out.t_ns = sec * 1000000000LL + usec * 1000LL;
  out.frame.can_id =
      static_cast<canid_t>(std::strtoul(std::string(frame, id_len).c_str(), nullptr, 16));
  if (id_len == 8) out.frame.can_id |= CAN_EFF_FLAG;
  const char* data = hash + 1;
  const std::size_t n = std::strlen(data) / 2;
  if (n > 8) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const char byte[3] = {data[2 * i], data[2 * i + 1], 0};
    out.frame.data[i] = static_cast<__u8>(std::strtoul(byte, nullptr, 16));
  }
  out.frame.can_dlc = static_cast<__u8>(n);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5 || argc > 7) {
    std::fprintf(stderr,
                 "usage: vm_feeder DATASET VIDEO_DEV CAN_IF SLOWDOWN [GO_FILE [EVENTS_CSV]]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const double slowdown = std::atof(argv[4]);
  if (!(slowdown >= 1.0 && slowdown <= 100.0)) die("SLOWDOWN must be 1..100");
  const std::vector<unsigned char> meta_bytes = read_file(dir + "/metadata.toml");
  const std::string metadata(meta_bytes.begin(), meta_bytes.end());
  const int meta_w = meta_int(metadata, "width_px"), meta_h = meta_int(metadata, "height_px");

  std::vector<FrameEntry> frames;
  {
    std::ifstream in(dir + "/frames.csv");
    if (!in) die("cannot open " + dir + "/frames.csv");
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      const auto comma = line.find(',');
      if (comma == std::string::npos) continue;
      frames.push_back({std::atoll(line.c_str()), dir + "/" + line.substr(comma + 1)});
    }
  }
  std::vector<CanEntry> cans;
  {
    std::ifstream in(dir + "/encoders.log");
    if (!in) die("cannot open " + dir + "/encoders.log");
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      CanEntry e;
      if (!parse_candump(line, e))
        die("encoders.log:" + std::to_string(n) + ": not a candump line");
      cans.push_back(e);
    }
  }
  if (frames.empty()) die("no frames");

  // The camera: the output side of the loopback, in the frames' format.
  const Pixels first = load_frame(frames[0].path, meta_w, meta_h);
  const int video = ::open(argv[2], O_RDWR);
  if (video < 0) die(std::string(argv[2]) + ": " + std::strerror(errno));
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  fmt.fmt.pix.width = static_cast<__u32>(first.width);
  fmt.fmt.pix.height = static_cast<__u32>(first.height);
  fmt.fmt.pix.pixelformat = first.rgb ? V4L2_PIX_FMT_RGB24 : V4L2_PIX_FMT_YUYV;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  fmt.fmt.pix.bytesperline = static_cast<__u32>(first.width * (first.rgb ? 3 : 2));
  fmt.fmt.pix.sizeimage = fmt.fmt.pix.bytesperline * static_cast<__u32>(first.height);
  fmt.fmt.pix.colorspace = V4L2_COLORSPACE_SRGB;
  if (::ioctl(video, VIDIOC_S_FMT, &fmt) != 0)
    die(std::string("VIDIOC_S_FMT: ") + std::strerror(errno));
  const std::size_t frame_size = fmt.fmt.pix.sizeimage;
  if (fmt.fmt.pix.width != static_cast<__u32>(first.width) ||
      fmt.fmt.pix.height != static_cast<__u32>(first.height))
    die("the loopback did not take the frame size");
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  parm.parm.output.timeperframe.numerator = static_cast<__u32>(slowdown * 1000.0 + 0.5);
  parm.parm.output.timeperframe.denominator =
      static_cast<__u32>(meta_int(metadata, "rate_hz") * 1000);
  if (meta_int(metadata, "rate_hz") > 0) (void)::ioctl(video, VIDIOC_S_PARM, &parm);
  auto write_frame = [&](const Pixels& p) {
    const ssize_t n = ::write(video, p.bytes.data() + p.offset, frame_size);
    if (n != static_cast<ssize_t>(frame_size))
      die(std::string("write to the loopback: ") + std::strerror(errno));
  };
  write_frame(first);  // the pre-roll: the capture node appears

  // The encoder bus.
  const int can = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (can < 0) die(std::string("CAN socket: ") + std::strerror(errno));
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, argv[3], IFNAMSIZ - 1);
  if (::ioctl(can, SIOCGIFINDEX, &ifr) != 0)
    die(std::string("CAN interface ") + argv[3] + ": " + std::strerror(errno));
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(can, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0)
    die(std::string("CAN bind: ") + std::strerror(errno));

  std::printf("FEEDER ready frames=%zu can=%zu size=%dx%d format=%s\n", frames.size(), cans.size(),
              first.width, first.height, first.rgb ? "rgb24" : "yuyv");
  std::fflush(stdout);
  if (argc >= 6) {
    const std::int64_t give_up = mono_ns() + 300LL * 1000000000LL;
    while (::access(argv[5], F_OK) != 0) {
      if (mono_ns() > give_up) die(std::string("no ") + argv[5] + " within 300 s");
      ::usleep(20000);
    }
  }

  const std::int64_t origin =
      std::min(frames.front().t_ns, cans.empty() ? frames.front().t_ns : cans.front().t_ns);
  const std::int64_t start = mono_ns() + 100000000LL;  // 0.1 s to set out
  auto wall = [&](std::int64_t t) {
    return start + static_cast<std::int64_t>(slowdown * static_cast<double>(t - origin));
  };
  std::printf("FEEDER start_mono_ns=%" PRId64 " origin_ns=%" PRId64 " slowdown=%g\n", start, origin,
              slowdown);
  std::fflush(stdout);

  std::size_t fi = 0, ci = 0;
  struct Sent {
    char kind;
    std::int64_t t_ns, sent_mono_ns, done_mono_ns;
  };
  std::vector<Sent> sent;
  sent.reserve(frames.size() + cans.size());
  Pixels next = first;
  while (fi < frames.size() || ci < cans.size()) {
    const bool frame_next =
        ci >= cans.size() || (fi < frames.size() && frames[fi].t_ns <= cans[ci].t_ns);
    sleep_until(wall(frame_next ? frames[fi].t_ns : cans[ci].t_ns));
    const std::int64_t out_ns = mono_ns();  // when it starts to go out
    if (frame_next) {
      write_frame(next);
      sent.push_back({'f', frames[fi].t_ns, out_ns, mono_ns()});
      ++fi;
      if (fi < frames.size())
        next = load_frame(frames[fi].path, meta_w, meta_h);  // before it is due
    } else {
      if (::write(can, &cans[ci].frame, sizeof(can_frame)) !=
          static_cast<ssize_t>(sizeof(can_frame)))
        die(std::string("CAN write: ") + std::strerror(errno));
      sent.push_back({'c', cans[ci].t_ns, out_ns, mono_ns()});
      ++ci;
    }
  }
  // How late each event began to go out against its place in the schedule.
  const std::int64_t late_ns = 10000000LL;
  std::int64_t frame_late_max = 0, can_late_max = 0;
  int frames_late = 0, cans_late = 0;
  std::vector<std::int64_t> frame_lates;
  for (const Sent& e : sent) {
    const std::int64_t late = e.sent_mono_ns - wall(e.t_ns);
    if (e.kind == 'f') {
      frame_late_max = std::max(frame_late_max, late);
      frame_lates.push_back(late);
      frames_late += late > late_ns ? 1 : 0;
    } else {
      can_late_max = std::max(can_late_max, late);
      cans_late += late > late_ns ? 1 : 0;
    }
  }
  std::sort(frame_lates.begin(), frame_lates.end());
  const double frame_late_p50_ms = static_cast<double>(frame_lates[frame_lates.size() / 2]) * 1e-6;
  std::printf(
      "FEEDER done frames=%zu can=%zu frame_late_p50_ms=%.2f frame_late_max_ms=%.1f "
      "can_late_max_ms=%.1f frames_late_over_10ms=%d "
      "can_late_over_10ms=%d wall_s=%.2f\n",
      fi, ci, frame_late_p50_ms, static_cast<double>(frame_late_max) * 1e-6,
      static_cast<double>(can_late_max) * 1e-6, frames_late, cans_late,
      static_cast<double>(mono_ns() - start) * 1e-9);
  std::fflush(stdout);
  if (argc == 7) {
    std::FILE* events = std::fopen(argv[6], "w");
    if (events == nullptr) die(std::string(argv[6]) + ": " + std::strerror(errno));
    std::fprintf(events, "kind,t_ns,sent_mono_ns,done_mono_ns\n");
    for (const Sent& e : sent)
      std::fprintf(events, "%c,%" PRId64 ",%" PRId64 ",%" PRId64 "\n", e.kind, e.t_ns,
                   e.sent_mono_ns, e.done_mono_ns);
    if (std::fclose(events) != 0) die(std::string(argv[6]) + ": " + std::strerror(errno));
  }
  ::close(can);
  ::close(video);
  return 0;
}
