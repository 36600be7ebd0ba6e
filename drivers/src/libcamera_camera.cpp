#include "harmoloc/drivers/libcamera_camera.hpp"

#include <cerrno>
#include <cstring>

#include <libcamera/libcamera.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <unistd.h>

namespace harmoloc::drivers {

namespace {

void bump(int fd) {
  const std::uint64_t one = 1;
  while (::write(fd, &one, sizeof one) < 0 && errno == EINTR) {
  }
}

void drain_eventfd(int fd) {
  std::uint64_t value = 0;
  while (::read(fd, &value, sizeof value) < 0 && errno == EINTR) {
  }
}

}  // namespace

LibcameraCamera::LibcameraCamera(hal::Clock& clock) : clock_(clock) {}

LibcameraCamera::~LibcameraCamera() {
  shutdown();
}

std::vector<std::string> LibcameraCamera::list_cameras() {
  std::vector<std::string> ids;
  libcamera::CameraManager manager;
  if (manager.start() != 0) return ids;
  for (const auto& c : manager.cameras()) ids.push_back(c->id());
  manager.stop();
  return ids;
}

std::string LibcameraCamera::open(const LibcameraOptions& options) {
  options_ = options;
  if (options.buffers < 2 || options.buffers > kMaxBuffers)
    return "camera.buffers must be 2.." + std::to_string(kMaxBuffers);
  completed_fd_ = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  released_fd_ = ::eventfd(0, EFD_CLOEXEC);
  if (completed_fd_ < 0 || released_fd_ < 0) return std::string("eventfd: ") + std::strerror(errno);

  manager_ = std::make_unique<libcamera::CameraManager>();
  if (const int rc = manager_->start(); rc != 0)
    return std::string("libcamera: cannot start the camera manager: ") + std::strerror(-rc);
  const auto cameras = manager_->cameras();
  if (cameras.empty()) return "libcamera: no camera found";
  if (options.camera_id.empty()) {
    camera_ = cameras.front();
  } else {
    camera_ = manager_->get(options.camera_id);
    if (!camera_) {
      std::string list;
      for (const auto& c : cameras) list += (list.empty() ? "" : ", ") + c->id();
      return "libcamera: no camera '" + options.camera_id + "' (found: " + list + ")";
    }
  }
  const std::string where = "libcamera camera " + camera_->id() + ": ";
  if (camera_->acquire() != 0) return where + "in use by another program";
  acquired_ = true;

  std::unique_ptr<libcamera::CameraConfiguration> config =
      camera_->generateConfiguration({libcamera::StreamRole::Viewfinder});
  if (!config || config->size() != 1) return where + "no viewfinder stream";
  libcamera::StreamConfiguration& sc = config->at(0);
  // Our RGB24 (bytes R, G, B) is libcamera's BGR888 (DRM fourcc order).
  const auto offered = [&](const libcamera::PixelFormat& f) {
    for (const libcamera::PixelFormat& p : sc.formats().pixelformats())
      if (p == f) return true;
    return false;
  };
  libcamera::PixelFormat want;
  if (options.format != FormatRequest::kRgb24 && offered(libcamera::formats::YUYV)) {
    want = libcamera::formats::YUYV;
  } else if (options.format != FormatRequest::kYuyv && offered(libcamera::formats::BGR888)) {
    want = libcamera::formats::BGR888;
  } else {
    return where + "offers no " +
           (options.format == FormatRequest::kRgb24  ? "RGB24 (BGR888)"
            : options.format == FormatRequest::kYuyv ? "YUYV"
                                                     : "YUYV or RGB24 (BGR888)") +
           " format";
  }
  sc.pixelFormat = want;
  sc.size = libcamera::Size(options.width_px, options.height_px);
  sc.bufferCount = options.buffers;
  const libcamera::CameraConfiguration::Status status = config->validate();
  if (status == libcamera::CameraConfiguration::Invalid) return where + "configuration invalid";
  if (sc.pixelFormat != want || sc.size.width != options.width_px ||
      sc.size.height != options.height_px) {
    return where + "asked for " + want.toString() + " " + std::to_string(options.width_px) + "x" +
           std::to_string(options.height_px) + ", the camera gives " + sc.pixelFormat.toString() +
           " " + sc.size.toString();
  }
  if (camera_->configure(config.get()) != 0) return where + "configure failed";
  format_ = want == libcamera::formats::YUYV ? hal::PixelFormat::kYuyv : hal::PixelFormat::kRgb24;
  stride_bytes_ = sc.stride;
  if (stride_bytes_ < min_stride_bytes(format_, options.width_px))
    return where + "stride " + std::to_string(stride_bytes_) + " is too small";
  stream_ = sc.stream();

  allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
  if (allocator_->allocate(stream_) < 0) return where + "cannot allocate buffers";
  const auto& buffers = allocator_->buffers(stream_);
  if (buffers.size() > kMaxBuffers) return where + "too many buffers";
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    libcamera::FrameBuffer* buffer = buffers[i].get();
    const auto& planes = buffer->planes();
    if (planes.empty()) return where + "a buffer without planes";
    // A packed format has one plane; map it once, at start-up.
    const libcamera::FrameBuffer::Plane& plane = planes[0];
    const std::size_t need = std::size_t{stride_bytes_} * options.height_px;
    if (plane.length < need) return where + "a buffer is smaller than one image";
    void* p = ::mmap(nullptr, std::size_t{plane.offset} + plane.length, PROT_READ, MAP_SHARED,
                     plane.fd.get(), 0);
    if (p == MAP_FAILED) return where + "mmap: " + std::strerror(errno);
    mappings_.push_back(Mapping{p, std::size_t{plane.offset} + plane.length,
                                static_cast<const std::uint8_t*>(p) + plane.offset});
    std::unique_ptr<libcamera::Request> request = camera_->createRequest(i);
    if (!request) return where + "cannot create a request";
    if (request->addBuffer(stream_, buffer) != 0) return where + "cannot add a buffer";
    requests_.push_back(std::move(request));
  }
  camera_->requestCompleted.connect(this, &LibcameraCamera::on_request_completed);
  if (camera_->start() != 0) return where + "cannot start";
  started_ = true;
  for (auto& r : requests_) {
    if (camera_->queueRequest(r.get()) != 0) return where + "cannot queue a request";
  }
  requeuer_ = std::thread([this] { requeue_loop(); });
  description_ =
      camera_->id() + " " + sc.toString() + ", " + std::to_string(buffers.size()) + " buffers";
  return {};
}

void LibcameraCamera::on_request_completed(libcamera::Request* request) {
  // libcamera's thread. No locks, no allocation: a pointer into the ring and a wake-up.
  if (request->status() == libcamera::Request::RequestCancelled) {
    cancelled_.fetch_add(1, std::memory_order_relaxed);
    return;  // stopping
  }
  if (!completed_.push(request)) {
    // Cannot happen with one ring slot per request; requeue rather than lose the buffer.
    released_.push(request);
    bump(released_fd_);
    return;
  }
  bump(completed_fd_);
}

void LibcameraCamera::requeue_loop() {
  for (;;) {
    drain_eventfd(released_fd_);  // blocks until release() or shutdown bumps it
    if (stopping_.load(std::memory_order_acquire)) return;
    libcamera::Request* r = nullptr;
    while (released_.pop(r)) {
      r->reuse(libcamera::Request::ReuseBuffers);
      camera_->queueRequest(r);
    }
  }
}

hal::CameraStatus LibcameraCamera::acquire(hal::FrameView& frame, std::uint64_t deadline_ns) {
  if (held_ != nullptr) release();
  libcamera::Request* request = nullptr;
  for (;;) {
    if (completed_.pop(request)) break;
    const std::uint64_t now = clock_.now_ns();
    if (now >= deadline_ns) return hal::CameraStatus::kNoFrame;
    const std::uint64_t left_ns = deadline_ns - now;
    timespec timeout{static_cast<time_t>(left_ns / 1000000000ULL),
                     static_cast<long>(left_ns % 1000000000ULL)};
    pollfd p{completed_fd_, POLLIN, 0};
    const int rc = ::ppoll(&p, 1, &timeout, nullptr);
    if (rc > 0) {
      std::uint64_t value = 0;
      if (::read(completed_fd_, &value, sizeof value) < 0) {
      }
    } else if (rc == 0) {
      if (!completed_.pop(request)) return hal::CameraStatus::kNoFrame;
      break;
    }
  }
  // Keep the newest: older completed requests go straight back.
  libcamera::Request* newer = nullptr;
  bool skipped = false;
  while (completed_.pop(newer)) {
    ++counters_.dropped;
    released_.push(request);
    request = newer;
    skipped = true;
  }
  if (skipped) bump(released_fd_);

  libcamera::FrameBuffer* buffer = request->findBuffer(stream_);
  const std::uint64_t index = request->cookie();
  if (buffer == nullptr || index >= mappings_.size()) {
    ++counters_.corrupt;
    released_.push(request);
    bump(released_fd_);
    return hal::CameraStatus::kCorrupt;
  }
  const libcamera::FrameMetadata& meta = buffer->metadata();
  sequence_.next(meta.sequence);
  const std::size_t need = std::size_t{stride_bytes_} * options_.height_px;
  if (request->status() != libcamera::Request::RequestComplete ||
      meta.status != libcamera::FrameMetadata::FrameSuccess || meta.planes().empty() ||
      meta.planes()[0].bytesused < need) {
    ++counters_.corrupt;
    released_.push(request);
    bump(released_fd_);
    return hal::CameraStatus::kCorrupt;
  }
  held_ = request;
  ++counters_.frames;
  frame.data = mappings_[index].address;
  frame.width_px = options_.width_px;
  frame.height_px = options_.height_px;
  frame.stride_bytes = stride_bytes_;
  frame.format = format_;
  frame.timestamp_ns = meta.timestamp;  // the V4L2 buffer's CLOCK_MONOTONIC time
  frame.sequence = meta.sequence;
  return hal::CameraStatus::kFrame;
}

void LibcameraCamera::release() {
  if (held_ == nullptr) return;
  released_.push(held_);
  held_ = nullptr;
  bump(released_fd_);
}

hal::CameraCounters LibcameraCamera::counters() const {
  hal::CameraCounters c = counters_;
  c.dropped += sequence_.dropped();
  return c;
}

void LibcameraCamera::shutdown() {
  if (requeuer_.joinable()) {
    stopping_.store(true, std::memory_order_release);
    bump(released_fd_);
    requeuer_.join();
  }
  if (started_) camera_->stop();
  started_ = false;
  if (camera_) camera_->requestCompleted.disconnect(this, &LibcameraCamera::on_request_completed);
  requests_.clear();
  for (const Mapping& m : mappings_) ::munmap(m.base, m.length);
  mappings_.clear();
  if (allocator_ && stream_ != nullptr) allocator_->free(stream_);
  allocator_.reset();
  if (acquired_) camera_->release();
  acquired_ = false;
  camera_.reset();
  if (manager_) manager_->stop();
  manager_.reset();
  if (completed_fd_ >= 0) ::close(completed_fd_);
  if (released_fd_ >= 0) ::close(released_fd_);
  completed_fd_ = released_fd_ = -1;
}

}  // namespace harmoloc::drivers
