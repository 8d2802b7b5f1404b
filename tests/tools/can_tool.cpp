// can_tool: drives canopen::socketcan::SocketCanChannel from the command line
// for the system tests (real SocketCAN inside user-mode Linux).
//
//   can_tool send IFACE [--queue N]   send the frames read from stdin (text
//                                     form, one per line) in order; waits until
//                                     all are written, then prints counters
//   can_tool recv IFACE COUNT [SECS]  print COUNT received frames (text form)
//                                     and exit; exit 1 on timeout
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "canopen/socketcan/channel.hpp"

using canopen::can::Frame;
using namespace std::chrono_literals;

namespace {

int usage() {
  std::fputs("usage: can_tool send IFACE [--queue N] < frames | can_tool recv IFACE COUNT [SECS]\n", stderr);
  return 2;
}

int do_send(const std::string& iface, std::size_t queue) {
  std::vector<Frame> frames;
  std::string line;
  while (std::getline(std::cin, line)) {
    if (line.empty()) continue;
    auto f = canopen::can::parse_frame(line);
    if (!f) {
      std::fprintf(stderr, "can_tool: bad frame '%s'\n", line.c_str());
      return 2;
    }
    frames.push_back(*f);
  }
  boost::asio::io_context io;
  auto monitor = canopen::socketcan::LinkMonitor::create(io);
  canopen::socketcan::ChannelOptions opts;
  opts.tx_queue_capacity = queue;
  auto ch = canopen::socketcan::SocketCanChannel::open(io, iface, monitor, opts);
  std::size_t next = 0;
  std::size_t queue_full = 0;
  boost::asio::steady_timer timer(io);
  // Feed the bounded queue as fast as it accepts; on QueueFull wait a little.
  std::function<void()> feed = [&] {
    while (next < frames.size()) {
      const auto st = ch->send(frames[next]);
      if (st == canopen::can::SendStatus::QueueFull) {
        ++queue_full;
        break;
      }
      if (st == canopen::can::SendStatus::Invalid) {
        std::fprintf(stderr, "can_tool: channel refused frame %zu\n", next);
        io.stop();
        return;
      }
      ++next;
    }
    if (next == frames.size() && ch->stats().tx_queue_depth == 0) {
      ch->close();
      monitor->stop();
      return;
    }
    timer.expires_after(1ms);
    timer.async_wait([&](const boost::system::error_code& ec) {
      if (!ec) feed();
    });
  };
  feed();
  io.run();
  const auto s = ch->stats();
  // queue_full counts refusals by the bounded queue; those frames were resent.
  std::printf("sent %llu retries %llu dropped %llu queue_full %zu high_water %zu\n",
              static_cast<unsigned long long>(s.tx_frames), static_cast<unsigned long long>(s.tx_retries),
              static_cast<unsigned long long>(s.tx_dropped - queue_full), queue_full, s.tx_queue_high_water);
  return s.tx_frames == frames.size() ? 0 : 1;
}

int do_recv(const std::string& iface, std::size_t count, int secs) {
  boost::asio::io_context io;
  auto monitor = canopen::socketcan::LinkMonitor::create(io);
  auto ch = canopen::socketcan::SocketCanChannel::open(io, iface, monitor);
  std::size_t got = 0;
  int rc = 1;
  boost::asio::steady_timer deadline(io);
  auto stop = [&] {
    ch->close();
    monitor->stop();
    deadline.cancel();
  };
  ch->on_frames([&](std::span<const Frame> frames) {
    for (const auto& f : frames) {
      if (got == count) break;
      std::printf("%s\n", canopen::can::to_string(f).c_str());
      ++got;
    }
    if (got == count) {
      rc = 0;
      stop();
    }
  });
  deadline.expires_after(std::chrono::seconds(secs));
  deadline.async_wait([&](const boost::system::error_code& ec) {
    if (!ec) stop();
  });
  std::printf("ready\n");
  std::fflush(stdout);
  io.run();
  std::fflush(stdout);
  if (rc != 0) std::fprintf(stderr, "can_tool: timeout after %zu of %zu frames\n", got, count);
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> a(argv + 1, argv + argc);
  try {
    if (a.size() >= 2 && a[0] == "send") {
      std::size_t queue = 256;
      if (a.size() == 4 && a[2] == "--queue") queue = std::stoul(a[3]);
      return do_send(a[1], queue);
    }
    if (a.size() >= 3 && a[0] == "recv") return do_recv(a[1], std::stoul(a[2]), a.size() > 3 ? std::stoi(a[3]) : 30);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "can_tool: %s\n", e.what());
    return 1;
  }
  return usage();
}
