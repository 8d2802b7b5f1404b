// SocketCAN channel: one raw CAN socket on one interface, driven by a
// boost::asio::io_context.
//
// - Reception: recvmmsg() in batches, so a saturated bus costs one wake-up
//   per batch; kernel receive timestamps; SO_RXQ_OVFL drop counting; error
//   frames folded into bus-state events.
// - Transmission: a bounded queue (can::TxQueue) that survives ENOBUFS and
//   EAGAIN without reordering, dropping or blocking the loop.
// - Link changes: interface down/up and removal/re-creation are detected
//   (LinkMonitor) and the socket is reopened without restarting anything.
//
// Thread safety: create, use and close from the io_context's thread only.
// Lifetime: handlers keep the channel alive; call close() to stop it.
#pragma once

#include <linux/can.h>
#include <sys/socket.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/steady_timer.hpp>

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "canopen/can/channel.hpp"
#include "canopen/can/tx_queue.hpp"
#include "canopen/socketcan/link_monitor.hpp"

namespace canopen::socketcan {

// Raised by SocketCanChannel::open() when the interface cannot be used at
// start-up. what() is one line meant for the operator.
class CanUnavailable : public std::runtime_error {
 public:
  enum class Reason { NoKernelSupport, NoSuchInterface, NotCanInterface, SystemError };
  CanUnavailable(Reason r, const std::string& msg) : std::runtime_error(msg), reason_(r) {}
  Reason reason() const { return reason_; }

 private:
  Reason reason_;
};

struct ChannelOptions {
  std::size_t tx_queue_capacity = 4096;
  unsigned rx_batch = 64;         // frames per recvmmsg()
  unsigned rx_budget = 2048;      // frames per wake-up before yielding to other work
  int rcvbuf_bytes = 8 << 20;     // socket receive buffer (SO_RCVBUFFORCE when permitted)
  bool error_frames = true;       // subscribe to all error classes
};

class SocketCanChannel final : public can::Channel, public std::enable_shared_from_this<SocketCanChannel> {
 public:
  // Opens `ifname`. Throws CanUnavailable when the kernel lacks CAN, the
  // interface does not exist or is not CAN. An interface that exists but is
  // down is accepted: the channel starts in BusState::Down and comes up with it.
  static std::shared_ptr<SocketCanChannel> open(boost::asio::io_context& io, std::string ifname,
                                                std::shared_ptr<LinkMonitor> monitor, ChannelOptions opts = {});
  ~SocketCanChannel() override;

  std::string_view name() const override { return name_; }
  can::SendStatus send(const can::Frame& frame) override;
  can::BusState state() const override { return tracker_.state(); }
  can::ChannelStats stats() const override;
  bool fd_capable() const { return fd_capable_; }

  // Stops reading and writing, closes the socket. Queued frames are dropped.
  void close();

 private:
  SocketCanChannel(boost::asio::io_context& io, std::string ifname, std::shared_ptr<LinkMonitor> monitor,
                   ChannelOptions opts);
  void open_socket();  // throws CanUnavailable
  void close_socket();
  void start();
  void wait_readable();
  void on_readable();
  void handle_error_frame(const can::ErrorFrameInfo& info);
  void note_drop_count(std::uint32_t count);
  void flush_tx();
  void arm_retry(Duration delay);
  void recheck_link();
  void emit(const std::optional<can::BusEvent>& ev);

  boost::asio::io_context& io_;
  std::string name_;
  std::shared_ptr<LinkMonitor> monitor_;
  LinkMonitor::ListenerId listener_ = 0;
  ChannelOptions opts_;
  boost::asio::posix::stream_descriptor sd_;
  boost::asio::steady_timer retry_timer_;
  unsigned ifindex_ = 0;
  bool fd_capable_ = false;
  bool closed_ = false;
  // Bumped whenever the socket is replaced, so completions for the old one are ignored.
  std::uint64_t generation_ = 0;

  enum class TxWait { None, Writable, RetryTimer, Link };
  TxWait tx_wait_ = TxWait::None;
  can::TxQueue txq_;
  can::BusStateTracker tracker_;
  can::ChannelStats stats_;
  std::uint64_t invalid_tx_ = 0;
  std::uint32_t last_drop_count_ = 0;

  // recvmmsg() buffers, allocated once.
  std::vector<canfd_frame> rx_raw_;
  std::vector<iovec> rx_iov_;
  std::vector<mmsghdr> rx_msgs_;
  std::vector<char> rx_control_;
  std::vector<can::Frame> rx_batch_;
  // sendmmsg() buffers.
  static constexpr std::size_t kTxBatch = 64;
  std::vector<canfd_frame> tx_raw_;
  std::vector<iovec> tx_iov_;
  std::vector<mmsghdr> tx_msgs_;
};

}  // namespace canopen::socketcan
