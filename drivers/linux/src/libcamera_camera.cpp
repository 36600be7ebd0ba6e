#include "harmoloc/drivers/libcamera_camera.hpp"

#include <cerrno>
#include <cstring>

#include <libcamera/libcamera.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <unistd.h>

namespace harmoloc::drivers {

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
  if (const std::string e = handoff_.open(); !e.empty()) return e;

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
  // libcamera's thread. No locks, no allocation: a pointer into the ring and a wake-up. The ring
  // has room for every request (static_assert in the header); were it full, the request would
  // be lost and counted as an error (CompletionHandoff::full_count).
  if (request->status() == libcamera::Request::RequestCancelled) {
    cancelled_.fetch_add(1, std::memory_order_relaxed);
    return;  // stopping
  }
  handoff_.complete(request);
}

void LibcameraCamera::requeue_loop() {
  while (handoff_.wait_given_back([this](libcamera::Request* r) {
    r->reuse(libcamera::Request::ReuseBuffers);
    camera_->queueRequest(r);
  })) {
  }
}

hal::CameraStatus LibcameraCamera::acquire(hal::FrameView& frame, std::uint64_t deadline_ns) {
  if (held_ != nullptr) release();
  // The newest completed request; older ones go straight back (counted as dropped).
  libcamera::Request* request = nullptr;
  std::uint64_t skipped = 0;
  const bool got = handoff_.take_newest(request, deadline_ns, clock_, skipped);
  counters_.dropped += skipped;
  if (!got) return hal::CameraStatus::kNoFrame;

  libcamera::FrameBuffer* buffer = request->findBuffer(stream_);
  const std::uint64_t index = request->cookie();
  if (buffer == nullptr || index >= mappings_.size()) {
    ++counters_.corrupt;
    handoff_.give_back(request);
    return hal::CameraStatus::kCorrupt;
  }
  const libcamera::FrameMetadata& meta = buffer->metadata();
  sequence_.next(meta.sequence);
  const std::size_t need = std::size_t{stride_bytes_} * options_.height_px;
  if (request->status() != libcamera::Request::RequestComplete ||
      meta.status != libcamera::FrameMetadata::FrameSuccess || meta.planes().empty() ||
      meta.planes()[0].bytesused < need) {
    ++counters_.corrupt;
    handoff_.give_back(request);
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
  handoff_.give_back(held_);
  held_ = nullptr;
}

hal::CameraCounters LibcameraCamera::counters() const {
  hal::CameraCounters c = counters_;
  c.dropped += sequence_.dropped();
  c.errors += handoff_.full_count();
  return c;
}

void LibcameraCamera::shutdown() {
  if (requeuer_.joinable()) {
    handoff_.stop();
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
  handoff_.close();
}

}  // namespace harmoloc::drivers
