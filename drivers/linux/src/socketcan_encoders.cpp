#include "harmoloc/drivers/socketcan_encoders.hpp"

#include <cerrno>
#include <cstring>
#include <ctime>

#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

namespace harmoloc::drivers {

namespace {

std::uint64_t clock_ns(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL +
         static_cast<std::uint64_t>(ts.tv_nsec);
}

}  // namespace

SocketCanEncoders::~SocketCanEncoders() {
  if (fd_ >= 0) ::close(fd_);
}

std::string SocketCanEncoders::open(const SocketCanOptions& options) {
  options_ = options;
  const std::string where = "CAN interface " + options.interface + ": ";
  if (options.interface.empty() || options.interface.size() >= IFNAMSIZ)
    return where + "not a valid interface name";
  if (!algorithms::layout_valid(options.layout)) return where + "invalid frame layout";
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) return where + "socket(PF_CAN): " + std::strerror(errno) + " (is can-raw loaded?)";
  const unsigned index = ::if_nametoindex(options.interface.c_str());
  if (index == 0) return where + "no such interface";

  // Only our frame (standard or extended as the ID needs), unless every frame is wanted.
  const bool extended = options.layout.id > CAN_SFF_MASK;
  can_filter filter{};
  if (options.kernel_filter) {
    filter.can_id = extended ? (options.layout.id | CAN_EFF_FLAG) : options.layout.id;
    filter.can_mask = (extended ? CAN_EFF_MASK : CAN_SFF_MASK) | CAN_EFF_FLAG | CAN_RTR_FLAG;
  } else {
    filter.can_id = 0;
    filter.can_mask = 0;  // everything
  }
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, &filter, sizeof filter) < 0)
    return where + "CAN_RAW_FILTER: " + std::strerror(errno);
  // Error frames: bus-off, controller and protocol problems, lost arbitration, no ACK.
  can_err_mask_t errors = CAN_ERR_MASK;
  if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors) < 0)
    return where + "CAN_RAW_ERR_FILTER: " + std::strerror(errno);
  const int on = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) < 0)
    return where + "SO_TIMESTAMPNS: " + std::strerror(errno);
  // Frames the socket's queue had to drop arrive as a count with each datagram.
  ::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0)
    return where + "bind: " + std::strerror(errno);
  return {};
}

void SocketCanEncoders::handle_frame(const can_frame& frame, std::uint64_t timestamp_ns) {
  if ((frame.can_id & CAN_ERR_FLAG) != 0) {
    ++counters_.bus_errors;
    if ((frame.can_id & CAN_ERR_BUSOFF) != 0) ++counters_.bus_off;
    return;
  }
  if ((frame.can_id & CAN_RTR_FLAG) != 0) {
    ++counters_.ignored_id;  // a remote request carries no counters
    return;
  }
  algorithms::CanFrame f;
  f.extended = (frame.can_id & CAN_EFF_FLAG) != 0;
  f.id = frame.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  f.length = frame.can_dlc <= 8 ? frame.can_dlc : 8;
  std::memcpy(f.data.data(), frame.data, 8);
  f.timestamp_ns = timestamp_ns;
  // Standard and extended frames are different IDs even with the same number.
  if (f.extended != (options_.layout.id > CAN_SFF_MASK)) {
    ++counters_.ignored_id;
    return;
  }
  std::uint32_t left = 0, right = 0;
  switch (algorithms::decode_encoder_frame(options_.layout, f, left, right)) {
    case algorithms::CanDecode::kOtherId:
      ++counters_.ignored_id;
      return;
    case algorithms::CanDecode::kBadLength:
      ++counters_.bad_length;
      return;
    case algorithms::CanDecode::kOk:
      break;
  }
  if (ring_size_ == kRingCapacity) {  // the cycle stalled: the oldest sample goes
    ring_head_ = (ring_head_ + 1) % kRingCapacity;
    --ring_size_;
    ++counters_.overflows;
  }
  ring_[(ring_head_ + ring_size_) % kRingCapacity] = Sample{left, right, timestamp_ns};
  ++ring_size_;
}

void SocketCanEncoders::drain() {
  if (fd_ < 0) return;
  // Receive timestamps come on CLOCK_REALTIME; the data clock is CLOCK_MONOTONIC.
  const std::uint64_t realtime_now = clock_ns(CLOCK_REALTIME);
  const std::uint64_t monotonic_now = clock_ns(CLOCK_MONOTONIC);
  for (std::size_t n = 0; n < kMaxFramesPerRead; ++n) {
    can_frame frame{};
    iovec iov{&frame, sizeof frame};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(std::uint32_t))];
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t got = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (got < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK && !down_) {
        // ENETDOWN and friends: the interface went down or away. Counted once per episode.
        ++counters_.bus_errors;
        down_ = true;
      }
      return;
    }
    down_ = false;
    if (static_cast<std::size_t>(got) != sizeof frame) continue;  // CAN FD frames are not ours
    std::uint64_t timestamp_ns = monotonic_now;
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level != SOL_SOCKET) continue;
      if (c->cmsg_type == SO_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        const std::uint64_t real = static_cast<std::uint64_t>(ts.tv_sec) * 1000000000ULL +
                                   static_cast<std::uint64_t>(ts.tv_nsec);
        const std::uint64_t age = realtime_now > real ? realtime_now - real : 0;
        timestamp_ns = monotonic_now > age ? monotonic_now - age : 0;
      } else if (c->cmsg_type == SO_RXQ_OVFL) {
        std::uint32_t dropped = 0;
        std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
        // A running total for the socket: keep the highest seen.
        if (dropped > counters_.overflows) counters_.overflows = dropped;
      }
    }
    handle_frame(frame, timestamp_ns);
  }
}

hal::EncoderStatus SocketCanEncoders::read(std::uint64_t data_time_ns, hal::EncoderCounts& counts) {
  drain();
  bool fresh = false;
  while (ring_size_ > 0 && ring_[ring_head_].timestamp_ns <= data_time_ns) {
    const Sample& s = ring_[ring_head_];
    counts.left_ticks = s.left;
    counts.right_ticks = s.right;
    counts.counter_bits = options_.layout.counter_bits;
    counts.timestamp_ns = s.timestamp_ns;
    ring_head_ = (ring_head_ + 1) % kRingCapacity;
    --ring_size_;
    ++counters_.samples;
    fresh = true;
  }
  return fresh ? hal::EncoderStatus::kFresh : hal::EncoderStatus::kNoData;
}

}  // namespace harmoloc::drivers
