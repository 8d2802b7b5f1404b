// Watches network interfaces appear, disappear, go up and down, through an
// rtnetlink socket (RTMGRP_LINK) on the io_context; falls back to polling
// when netlink is not available. Channels subscribe and re-check their own
// interface when told something changed.
//
// Thread safety: use from the io_context's thread only.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>

namespace canopen::socketcan {

struct LinkInfo {
  bool exists = false;
  unsigned ifindex = 0;
  bool up = false;        // IFF_UP
  bool is_can = false;    // ARPHRD_CAN
  int mtu = 0;            // CAN_MTU (16) or CANFD_MTU (72) for CAN interfaces
};

// Current state of one interface, by name (ioctl; no netlink needed).
LinkInfo query_link(const std::string& ifname);

class LinkMonitor : public std::enable_shared_from_this<LinkMonitor> {
 public:
  // Called with the interface name that changed; an empty name means
  // "something may have changed" (polling fallback, or netlink overrun).
  using Listener = std::function<void(std::string_view ifname)>;
  using ListenerId = unsigned;

  static std::shared_ptr<LinkMonitor> create(boost::asio::io_context& io,
                                             std::chrono::milliseconds poll_interval = std::chrono::seconds(1));

  ListenerId subscribe(Listener l);
  void unsubscribe(ListenerId id);
  bool uses_netlink() const { return netlink_.is_open(); }
  void stop();

 private:
  explicit LinkMonitor(boost::asio::io_context& io, std::chrono::milliseconds poll_interval);
  void start();
  void wait_netlink();
  void read_netlink();
  void arm_poll();
  void notify(std::string_view ifname);

  boost::asio::posix::stream_descriptor netlink_;
  boost::asio::steady_timer poll_timer_;
  std::chrono::milliseconds poll_interval_;
  std::map<ListenerId, Listener> listeners_;
  ListenerId next_id_ = 1;
  bool stopped_ = false;
};

}  // namespace canopen::socketcan
