#include "harmoloc/drivers/v4l2_camera.hpp"

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

namespace harmoloc::drivers {

static_assert(kFourccYuyv == V4L2_PIX_FMT_YUYV, "YUYV fourcc");
static_assert(kFourccRgb24 == V4L2_PIX_FMT_RGB24, "RGB24 fourcc");

namespace {

int xioctl(int fd, unsigned long request, void* arg) {
  int rc;
  do {
    rc = ::ioctl(fd, request, arg);
  } while (rc < 0 && errno == EINTR);
  return rc;
}

std::string errno_text(const char* what) {
  return std::string(what) + ": " + std::strerror(errno);
}

}  // namespace

V4l2Camera::~V4l2Camera() {
  stop();
}

std::string V4l2Camera::open(const V4l2Options& options) {
  options_ = options;
  if (options_.buffers < 2 || options_.buffers > kMaxBuffers) {
    return "camera.buffers must be 2.." + std::to_string(kMaxBuffers);
  }
  std::string e = start();
  if (!e.empty()) {
    stop();
    return options_.device + ": " + e;
  }
  return {};
}

std::string V4l2Camera::start() {
  fd_ = ::open(options_.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) return std::strerror(errno);

  v4l2_capability cap{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) return errno_text("not a V4L2 device (QUERYCAP)");
  const std::uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0) return "not a single-planar video capture device";
  if ((caps & V4L2_CAP_STREAMING) == 0) return "the device cannot stream (no mmap I/O)";

  // Formats the device offers (bounded: a device lists a few dozen at most).
  std::array<std::uint32_t, 64> offered{};
  std::size_t count = 0;
  for (std::uint32_t i = 0; count < offered.size(); ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_ENUM_FMT, &d) < 0) break;
    offered[count++] = d.pixelformat;
  }
  const std::uint32_t want = choose_fourcc(options_.format, offered.data(), count);
  if (want == 0) {
    std::string list;
    for (std::size_t i = 0; i < count; ++i) list += (i ? " " : "") + fourcc_text(offered[i]);
    return std::string("offers no ") +
           (options_.format == FormatRequest::kRgb24  ? "RGB24"
            : options_.format == FormatRequest::kYuyv ? "YUYV"
                                                      : "YUYV or RGB24") +
           " format (it offers: " + (list.empty() ? "none" : list) + ")";
  }

  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = options_.width_px;
  fmt.fmt.pix.height = options_.height_px;
  fmt.fmt.pix.pixelformat = want;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (xioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) return errno_text("VIDIOC_S_FMT");
  if (fmt.fmt.pix.field != V4L2_FIELD_NONE && fmt.fmt.pix.field != V4L2_FIELD_ANY) {
    return "the device delivers interlaced fields; a progressive format is needed";
  }
  if (const std::string e = check_negotiated(
          want, options_.width_px, options_.height_px, fmt.fmt.pix.pixelformat, fmt.fmt.pix.width,
          fmt.fmt.pix.height, fmt.fmt.pix.bytesperline, fmt.fmt.pix.sizeimage);
      !e.empty()) {
    return e;
  }
  fourcc_ = want;
  format_ = pixel_format_of(want);
  stride_bytes_ = fmt.fmt.pix.bytesperline;
  image_bytes_ = stride_bytes_ * options_.height_px;

  v4l2_requestbuffers req{};
  req.count = options_.buffers;
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) return errno_text("VIDIOC_REQBUFS");
  if (req.count < 2) return "the device gave fewer than 2 buffers";
  buffer_count_ = req.count < kMaxBuffers ? req.count : kMaxBuffers;
  for (std::uint32_t i = 0; i < buffer_count_; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) return errno_text("VIDIOC_QUERYBUF");
    if (b.length < image_bytes_) return "a buffer is smaller than one image";
    void* p = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
    if (p == MAP_FAILED) return errno_text("mmap");
    buffers_[i] = Mapping{p, b.length};
  }
  for (std::uint32_t i = 0; i < buffer_count_; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) return errno_text("VIDIOC_QBUF");
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) return errno_text("VIDIOC_STREAMON");
  sequence_.restart();
  description_ = std::string(reinterpret_cast<const char*>(cap.card)) + " " +
                 std::to_string(options_.width_px) + "x" + std::to_string(options_.height_px) +
                 " " + fourcc_text(fourcc_) + ", " + std::to_string(buffer_count_) +
                 " mmap buffers";
  return {};
}

void V4l2Camera::stop() {
  if (fd_ >= 0) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    xioctl(fd_, VIDIOC_STREAMOFF, &type);
  }
  for (Mapping& m : buffers_) {
    if (m.address != nullptr) ::munmap(m.address, m.length);
    m = Mapping{};
  }
  if (fd_ >= 0) {
    // Free the driver's buffers so that a reopened device (or another process) can have them.
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    xioctl(fd_, VIDIOC_REQBUFS, &req);
    ::close(fd_);
  }
  fd_ = -1;
  buffer_count_ = 0;
  held_ = -1;
}

void V4l2Camera::fail_device() {
  ++counters_.errors;
  stop();
  next_reopen_ns_ = clock_.now_ns() + std::uint64_t{options_.reopen_interval_ms} * 1000000ULL;
}

void V4l2Camera::requeue(std::uint32_t index) {
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  b.index = index;
  if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) fail_device();
}

hal::CameraStatus V4l2Camera::acquire(hal::FrameView& frame, std::uint64_t deadline_ns) {
  if (held_ >= 0) release();  // the cycle forgot: never lose a buffer
  if (fd_ < 0) {
    // Unplugged or failed: reopen now and then; between attempts wait out the cycle's period
    // so that a loop without a camera still runs at its rate.
    const std::uint64_t now = clock_.now_ns();
    if (now >= next_reopen_ns_) {
      if (start().empty()) {
        ++counters_.reopens;
      } else {
        stop();
        next_reopen_ns_ = now + std::uint64_t{options_.reopen_interval_ms} * 1000000ULL;
      }
    }
    if (fd_ < 0) {
      clock_.sleep_until(deadline_ns);
      return hal::CameraStatus::kNoFrame;
    }
  }

  // Wait for a frame until the deadline (ppoll: nanosecond timeout, EINTR retried within it).
  for (;;) {
    const std::uint64_t now = clock_.now_ns();
    const std::uint64_t left_ns = deadline_ns > now ? deadline_ns - now : 0;
    timespec timeout{static_cast<time_t>(left_ns / 1000000000ULL),
                     static_cast<long>(left_ns % 1000000000ULL)};
    pollfd p{fd_, POLLIN, 0};
    const int rc = ::ppoll(&p, 1, &timeout, nullptr);
    if (rc < 0 && errno == EINTR) {
      if (left_ns == 0) return hal::CameraStatus::kNoFrame;
      continue;
    }
    if (rc < 0) {
      fail_device();
      return hal::CameraStatus::kNoFrame;
    }
    if (rc == 0) return hal::CameraStatus::kNoFrame;
    if ((p.revents & POLLIN) == 0) {
      // POLLERR without data: the queue is in error (vb2_queue_error) or the device is gone.
      fail_device();
      return hal::CameraStatus::kNoFrame;
    }
    break;
  }

  // Dequeue what is ready (at most every buffer); keep the newest unless told otherwise.
  v4l2_buffer got{};
  bool have = false;
  for (std::uint32_t n = 0; n < buffer_count_; ++n) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
      if (errno == EAGAIN) break;
      // EIO: the queue is in error; ENODEV: unplugged. Give back what we took and reopen later.
      fail_device();
      return hal::CameraStatus::kNoFrame;
    }
    if (b.index >= buffer_count_) {
      fail_device();
      return hal::CameraStatus::kNoFrame;
    }
    sequence_.next(b.sequence);
    if (have) {
      ++counters_.dropped;  // an older frame skipped to stay current
      requeue(got.index);
      if (fd_ < 0) return hal::CameraStatus::kNoFrame;
    }
    got = b;
    have = true;
    if (!options_.newest_frame) break;
  }
  if (!have) return hal::CameraStatus::kNoFrame;

  if ((got.flags & V4L2_BUF_FLAG_ERROR) != 0 || got.bytesused < image_bytes_) {
    ++counters_.corrupt;
    requeue(got.index);
    return hal::CameraStatus::kCorrupt;
  }
  std::uint64_t timestamp_ns = 0;
  if ((got.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    timestamp_ns = static_cast<std::uint64_t>(got.timestamp.tv_sec) * 1000000000ULL +
                   static_cast<std::uint64_t>(got.timestamp.tv_usec) * 1000ULL;
  } else {
    timestamp_ns = clock_.now_ns();  // the device gives no monotonic capture time
  }
  held_ = got.index;
  ++counters_.frames;
  frame.data = static_cast<const std::uint8_t*>(buffers_[got.index].address);
  frame.width_px = options_.width_px;
  frame.height_px = options_.height_px;
  frame.stride_bytes = stride_bytes_;
  frame.format = format_;
  frame.timestamp_ns = timestamp_ns;
  frame.sequence = got.sequence;
  return hal::CameraStatus::kFrame;
}

void V4l2Camera::release() {
  if (held_ < 0) return;
  const auto index = static_cast<std::uint32_t>(held_);
  held_ = -1;
  if (fd_ >= 0) requeue(index);
}

hal::CameraCounters V4l2Camera::counters() const {
  hal::CameraCounters c = counters_;
  c.dropped += sequence_.dropped();
  return c;
}

}  // namespace harmoloc::drivers
