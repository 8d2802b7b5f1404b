#include "canopen/socketcan/channel.hpp"

#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <unistd.h>

#include <boost/asio/post.hpp>

#include <cerrno>
#include <cstring>

#include "canopen/socketcan/codec.hpp"

namespace canopen::socketcan {

namespace {

std::string errno_text(int err) { return std::strerror(err); }

void set_opt(int fd, int level, int name, int value) {
  // Best effort: every option here has a safe default if the kernel refuses it.
  (void)::setsockopt(fd, level, name, &value, sizeof value);
}

}  // namespace

std::shared_ptr<SocketCanChannel> SocketCanChannel::open(boost::asio::io_context& io, std::string ifname,
                                                         std::shared_ptr<LinkMonitor> monitor, ChannelOptions opts) {
  std::shared_ptr<SocketCanChannel> ch(new SocketCanChannel(io, std::move(ifname), std::move(monitor), opts));
  ch->open_socket();
  ch->start();
  return ch;
}

SocketCanChannel::SocketCanChannel(boost::asio::io_context& io, std::string ifname,
                                   std::shared_ptr<LinkMonitor> monitor, ChannelOptions opts)
    : io_(io),
      name_(std::move(ifname)),
      monitor_(std::move(monitor)),
      opts_(opts),
      sd_(io),
      retry_timer_(io),
      txq_(opts.tx_queue_capacity) {
  if (opts_.rx_batch == 0) opts_.rx_batch = 1;
  rx_raw_.resize(opts_.rx_batch);
  rx_iov_.resize(opts_.rx_batch);
  rx_msgs_.resize(opts_.rx_batch);
  rx_control_.resize(opts_.rx_batch * kControlBufferSize);
  rx_batch_.reserve(opts_.rx_batch);
  tx_raw_.resize(kTxBatch);
  tx_iov_.resize(kTxBatch);
  tx_msgs_.resize(kTxBatch);
  for (unsigned i = 0; i < opts_.rx_batch; ++i) {
    rx_iov_[i] = {&rx_raw_[i], sizeof(canfd_frame)};
  }
}

SocketCanChannel::~SocketCanChannel() {
  boost::system::error_code ec;
  sd_.close(ec);
}

void SocketCanChannel::open_socket() {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT)
      throw CanUnavailable(CanUnavailable::Reason::NoKernelSupport,
                           "this kernel has no SocketCAN support (socket(PF_CAN): " + errno_text(err) +
                               "); load the can and can_raw modules");
    throw CanUnavailable(CanUnavailable::Reason::SystemError, "socket(PF_CAN) failed: " + errno_text(err));
  }
  const LinkInfo link = query_link(name_);
  if (!link.exists) {
    ::close(fd);
    throw CanUnavailable(CanUnavailable::Reason::NoSuchInterface, "CAN interface '" + name_ + "' does not exist");
  }
  if (!link.is_can) {
    ::close(fd);
    throw CanUnavailable(CanUnavailable::Reason::NotCanInterface, "interface '" + name_ + "' is not a CAN interface");
  }
  fd_capable_ = link.mtu == static_cast<int>(CANFD_MTU);
  set_opt(fd, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, 1);
  if (opts_.error_frames) set_opt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, static_cast<int>(CAN_ERR_MASK));
  set_opt(fd, SOL_SOCKET, SO_TIMESTAMPNS, 1);
  set_opt(fd, SOL_SOCKET, SO_RXQ_OVFL, 1);
  // A burst of frames while the loop is busy must fit: each CAN skb costs
  // ~1 KiB of buffer, so the default (~200 KiB) overflows after ~200 frames.
  if (::setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &opts_.rcvbuf_bytes, sizeof opts_.rcvbuf_bytes) != 0)
    set_opt(fd, SOL_SOCKET, SO_RCVBUF, opts_.rcvbuf_bytes);

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(link.ifindex);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    const int err = errno;
    ::close(fd);
    throw CanUnavailable(CanUnavailable::Reason::SystemError,
                         "cannot bind to CAN interface '" + name_ + "': " + errno_text(err));
  }
  sd_.assign(fd);
  ifindex_ = link.ifindex;
  last_drop_count_ = 0;
  ++generation_;
}

void SocketCanChannel::close_socket() {
  boost::system::error_code ec;
  sd_.close(ec);
  ++generation_;
}

void SocketCanChannel::start() {
  auto weak = weak_from_this();
  listener_ = monitor_->subscribe([weak](std::string_view ifname) {
    auto self = weak.lock();
    if (self && (ifname.empty() || ifname == self->name_)) self->recheck_link();
  });
  const LinkInfo link = query_link(name_);
  if (link.up) emit(tracker_.on_link_up());
  wait_readable();
}

void SocketCanChannel::close() {
  if (closed_) return;
  closed_ = true;
  monitor_->unsubscribe(listener_);
  retry_timer_.cancel();
  close_socket();
  txq_.clear();
}

void SocketCanChannel::emit(const std::optional<can::BusEvent>& ev) {
  if (ev) report(*ev);
}

can::ChannelStats SocketCanChannel::stats() const {
  can::ChannelStats s = stats_;
  s.tx_frames = txq_.written();
  s.tx_dropped = txq_.dropped() + txq_.failed() + invalid_tx_;
  s.tx_retries = txq_.retries();
  s.tx_queue_depth = txq_.size();
  s.tx_queue_high_water = txq_.high_water();
  return s;
}

// ---- reception -------------------------------------------------------------

void SocketCanChannel::wait_readable() {
  if (closed_ || !sd_.is_open()) return;
  sd_.async_wait(boost::asio::posix::stream_descriptor::wait_read,
                 [self = shared_from_this(), gen = generation_](const boost::system::error_code& ec) {
                   if (ec || gen != self->generation_ || self->closed_) return;
                   self->on_readable();
                 });
}

void SocketCanChannel::on_readable() {
  const std::uint64_t gen = generation_;
  const int fd = sd_.native_handle();
  unsigned total = 0;
  for (;;) {
    for (unsigned i = 0; i < opts_.rx_batch; ++i) {
      msghdr& h = rx_msgs_[i].msg_hdr;
      h = msghdr{};
      h.msg_iov = &rx_iov_[i];
      h.msg_iovlen = 1;
      h.msg_control = &rx_control_[i * kControlBufferSize];
      h.msg_controllen = kControlBufferSize;
    }
    const int n = ::recvmmsg(fd, rx_msgs_.data(), opts_.rx_batch, MSG_DONTWAIT, nullptr);
    if (n < 0) {
      const int err = errno;
      if (err == EINTR) continue;
      if (err == EAGAIN || err == EWOULDBLOCK) break;
      // ENETDOWN / ENODEV: the interface went down or away. The link
      // monitor reports it too; checking now makes it independent of that.
      recheck_link();
      if (gen != generation_ || closed_) return;
      break;
    }
    rx_batch_.clear();
    for (int i = 0; i < n; ++i) {
      const msghdr& h = rx_msgs_[static_cast<unsigned>(i)].msg_hdr;
      const RxMeta meta = parse_control(h);
      if (meta.drop_count) note_drop_count(*meta.drop_count);
      const Decoded d = decode(rx_raw_[static_cast<unsigned>(i)], rx_msgs_[static_cast<unsigned>(i)].msg_len);
      if (d.kind == RawKind::Data) {
        rx_batch_.push_back(d.frame);
        // The kernel's time when it gave one; the clock only when not.
        rx_batch_.back().timestamp = meta.timestamp ? *meta.timestamp : can::Frame::Clock::now();
      } else if (d.kind == RawKind::Error) {
        // Keep bus order: frames before the error frame are delivered first.
        stats_.rx_frames += rx_batch_.size();
        deliver(rx_batch_);
        rx_batch_.clear();
        if (gen != generation_ || closed_) return;
        handle_error_frame(d.error);
      }
    }
    stats_.rx_frames += rx_batch_.size();
    deliver(rx_batch_);
    if (gen != generation_ || closed_) return;
    total += static_cast<unsigned>(n);
    if (static_cast<unsigned>(n) < opts_.rx_batch) break;
    if (total >= opts_.rx_budget) {
      // Let timers and other sockets run; continue right after them.
      boost::asio::post(io_, [self = shared_from_this(), gen] {
        if (gen == self->generation_ && !self->closed_) self->on_readable();
      });
      return;
    }
  }
  wait_readable();
}

void SocketCanChannel::note_drop_count(std::uint32_t count) {
  if (count == last_drop_count_) return;
  const std::uint32_t lost = count - last_drop_count_;  // wraps correctly
  last_drop_count_ = count;
  stats_.rx_dropped += lost;
  can::BusEvent ev;
  ev.state = ev.previous = tracker_.state();
  ev.cause = can::BusEventCause::RxOverflow;
  ev.dropped = lost;
  report(ev);
}

void SocketCanChannel::handle_error_frame(const can::ErrorFrameInfo& info) {
  ++stats_.error_frames;
  auto ev = tracker_.on_error_frame(info);
  if (ev && ev->cause == can::BusEventCause::RxOverflow) {
    ++stats_.rx_dropped;  // the controller lost at least one frame
    ev->dropped = 1;
  }
  emit(ev);
  // The controller is usable again after a restart: resume a stalled queue.
  if (ev && ev->state == can::BusState::ErrorActive && tx_wait_ == TxWait::Link) flush_tx();
}

// ---- transmission ----------------------------------------------------------

can::SendStatus SocketCanChannel::send(const can::Frame& frame) {
  if (closed_ || !frame.valid() || (frame.fd() && !fd_capable_)) {
    ++invalid_tx_;
    return can::SendStatus::Invalid;
  }
  if (!txq_.push(frame)) return can::SendStatus::QueueFull;
  if (tx_wait_ == TxWait::None) flush_tx();
  return can::SendStatus::Accepted;
}

void SocketCanChannel::flush_tx() {
  tx_wait_ = TxWait::None;
  if (closed_) return;
  if (!sd_.is_open()) {
    tx_wait_ = TxWait::Link;
    return;
  }
  const int fd = sd_.native_handle();
  // One sendmmsg() per run of queued frames: a block transfer's sub-block
  // of 127 frames costs two syscalls instead of 127.
  const can::FlushResult r = txq_.flush_batch(
      [&](std::span<const can::Frame> run) {
        const std::size_t n = run.size();
        for (std::size_t i = 0; i < n; ++i) {
          const std::size_t len = encode(run[i], tx_raw_[i]);
          tx_iov_[i] = {&tx_raw_[i], len};
          tx_msgs_[i] = mmsghdr{};
          tx_msgs_[i].msg_hdr.msg_iov = &tx_iov_[i];
          tx_msgs_[i].msg_hdr.msg_iovlen = 1;
        }
        for (;;) {
          const int sent = ::sendmmsg(fd, tx_msgs_.data(), static_cast<unsigned>(n), MSG_DONTWAIT);
          if (sent >= 0) return can::BatchWrite{static_cast<std::size_t>(sent), can::WriteResult::Written};
          switch (errno) {
            case EINTR: continue;
            case EAGAIN: return can::BatchWrite{0, can::WriteResult::WouldBlock};
            case ENOBUFS: return can::BatchWrite{0, can::WriteResult::NoBuffers};
            case ENETDOWN:
            case ENODEV:
            case ENXIO: return can::BatchWrite{0, can::WriteResult::LinkDown};
            default: return can::BatchWrite{0, can::WriteResult::Failed};  // e.g. EINVAL: this frame never goes out
          }
        }
      },
      tx_raw_.size());
  auto self = shared_from_this();
  const std::uint64_t gen = generation_;
  switch (r) {
    case can::FlushResult::Drained: break;
    case can::FlushResult::WouldBlock:
      tx_wait_ = TxWait::Writable;
      sd_.async_wait(boost::asio::posix::stream_descriptor::wait_write,
                     [self, gen](const boost::system::error_code& ec) {
                       if (ec || gen != self->generation_ || self->closed_) return;
                       self->flush_tx();
                     });
      break;
    case can::FlushResult::NoBuffers:
      // ENOBUFS means the device queue is full; poll() would report the
      // socket writable at once, so back off on a timer instead.
      arm_retry(txq_.retry_delay());
      break;
    case can::FlushResult::LinkDown:
      tx_wait_ = TxWait::Link;
      // Not from inside send(): handlers must never run there.
      boost::asio::post(io_, [self] {
        if (!self->closed_) self->recheck_link();
      });
      break;
  }
}

void SocketCanChannel::arm_retry(Duration delay) {
  tx_wait_ = TxWait::RetryTimer;
  retry_timer_.expires_after(delay);
  retry_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || self->closed_) return;
    self->flush_tx();
  });
}

// ---- link changes ----------------------------------------------------------

void SocketCanChannel::recheck_link() {
  if (closed_) return;
  const LinkInfo link = query_link(name_);
  if (!link.exists || !link.up || !link.is_can) {
    if (!link.exists && sd_.is_open()) close_socket();  // the kernel unbound it anyway
    emit(tracker_.on_link_down(!link.exists));
    if (tx_wait_ == TxWait::None && !txq_.empty()) tx_wait_ = TxWait::Link;
    return;
  }
  bool reopened = false;
  if (!sd_.is_open() || link.ifindex != ifindex_) {
    close_socket();
    try {
      open_socket();
    } catch (const CanUnavailable&) {
      return;  // stays Down; the next link notification tries again
    }
    ++stats_.reopens;
    reopened = true;
    wait_readable();
  }
  fd_capable_ = link.mtu == static_cast<int>(CANFD_MTU);
  const auto ev = tracker_.on_link_up();
  emit(ev);
  if (closed_) return;
  // A wait for writability belonged to the old socket; a queue stalled on
  // the link resumes now. If the link never looked down (a transient write
  // error), retry on the timer rather than spin.
  if (reopened && tx_wait_ == TxWait::Writable) {
    flush_tx();
  } else if (tx_wait_ == TxWait::Link) {
    if (ev || reopened) flush_tx();
    else arm_retry(std::chrono::milliseconds(10));
  }
}

}  // namespace canopen::socketcan
