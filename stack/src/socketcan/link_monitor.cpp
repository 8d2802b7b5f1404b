#include "canopen/socketcan/link_monitor.hpp"

#include <linux/if_arp.h>
#include <linux/netlink.h>
#include <linux/rtnetlink.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

namespace canopen::socketcan {

namespace {

// A socket only for interface ioctls; any family reaches dev_ioctl.
int ioctl_socket() {
  static const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  return fd;
}

}  // namespace

LinkInfo query_link(const std::string& ifname) {
  LinkInfo info;
  if (ifname.empty() || ifname.size() >= IFNAMSIZ) return info;
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, ifname.data(), ifname.size());
  const int fd = ioctl_socket();
  if (fd < 0 || ::ioctl(fd, SIOCGIFINDEX, &ifr) < 0) return info;
  info.exists = true;
  info.ifindex = static_cast<unsigned>(ifr.ifr_ifindex);
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) == 0) info.up = (ifr.ifr_flags & IFF_UP) != 0;
  if (::ioctl(fd, SIOCGIFHWADDR, &ifr) == 0) info.is_can = ifr.ifr_hwaddr.sa_family == ARPHRD_CAN;
  if (::ioctl(fd, SIOCGIFMTU, &ifr) == 0) info.mtu = ifr.ifr_mtu;
  return info;
}

std::shared_ptr<LinkMonitor> LinkMonitor::create(boost::asio::io_context& io,
                                                 std::chrono::milliseconds poll_interval) {
  std::shared_ptr<LinkMonitor> m(new LinkMonitor(io, poll_interval));
  m->start();
  return m;
}

LinkMonitor::LinkMonitor(boost::asio::io_context& io, std::chrono::milliseconds poll_interval)
    : netlink_(io), poll_timer_(io), poll_interval_(poll_interval) {}

void LinkMonitor::start() {
  const int fd = ::socket(AF_NETLINK, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, NETLINK_ROUTE);
  if (fd >= 0) {
    sockaddr_nl addr{};
    addr.nl_family = AF_NETLINK;
    addr.nl_groups = RTMGRP_LINK;
    if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
      netlink_.assign(fd);
      wait_netlink();
      return;
    }
    ::close(fd);
  }
  arm_poll();
}

LinkMonitor::ListenerId LinkMonitor::subscribe(Listener l) {
  const ListenerId id = next_id_++;
  listeners_.emplace(id, std::move(l));
  return id;
}

void LinkMonitor::unsubscribe(ListenerId id) { listeners_.erase(id); }

void LinkMonitor::stop() {
  stopped_ = true;
  boost::system::error_code ec;
  netlink_.close(ec);
  poll_timer_.cancel();
  listeners_.clear();
}

void LinkMonitor::notify(std::string_view ifname) {
  // Copy: a listener may unsubscribe.
  auto copy = listeners_;
  for (auto& [id, l] : copy) {
    if (listeners_.count(id) != 0) l(ifname);
  }
}

void LinkMonitor::wait_netlink() {
  netlink_.async_wait(boost::asio::posix::stream_descriptor::wait_read,
                      [self = shared_from_this()](const boost::system::error_code& ec) {
                        if (ec || self->stopped_) return;
                        self->read_netlink();
                        self->wait_netlink();
                      });
}

// The rtnetlink macros are C casts; they are the documented way to walk messages.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wcast-align"
#pragma GCC diagnostic ignored "-Wsign-conversion"
void LinkMonitor::read_netlink() {
  std::vector<char> buf(16384);
  for (;;) {
    const ssize_t n = ::recv(netlink_.native_handle(), buf.data(), buf.size(), MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR) continue;
      // ENOBUFS: the kernel dropped notifications; re-check everything.
      if (errno == ENOBUFS) notify({});
      return;
    }
    auto len = static_cast<unsigned>(n);
    for (auto* h = reinterpret_cast<nlmsghdr*>(buf.data()); NLMSG_OK(h, len); h = NLMSG_NEXT(h, len)) {
      if (h->nlmsg_type != RTM_NEWLINK && h->nlmsg_type != RTM_DELLINK) continue;
      auto* ifi = static_cast<ifinfomsg*>(NLMSG_DATA(h));
      auto attr_len = static_cast<unsigned>(IFLA_PAYLOAD(h));
      std::string_view name;
      for (auto* a = IFLA_RTA(ifi); RTA_OK(a, attr_len); a = RTA_NEXT(a, attr_len)) {
        if (a->rta_type == IFLA_IFNAME) {
          name = std::string_view(static_cast<const char*>(RTA_DATA(a)));
          break;
        }
      }
      notify(name);
      if (stopped_) return;
    }
  }
}

#pragma GCC diagnostic pop

void LinkMonitor::arm_poll() {
  poll_timer_.expires_after(poll_interval_);
  poll_timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || self->stopped_) return;
    self->notify({});
    self->arm_poll();
  });
}

}  // namespace canopen::socketcan
