// canopen-sim: simulated CANopen nodes on a SocketCAN interface.
//
//   canopen-sim --can IFACE --node N=EDSFILE [--node ff=EDSFILE] [--node ...] [--heartbeat MS]
//               [--tpdo-period MS] [--emcy-period MS] [--sync-period MS] [--auto-start]
//
// Prints one line per important event on stdout ("ready", "node 5 boot-up",
// "node 5 state operational", "node 5 emcy 3210", "node 5 rpdo 1 ...").
// Exit 0 on SIGINT/SIGTERM; 2 on a bad command line or EDS file; 3 when the
// CAN interface cannot be used. Errors are one line on stderr.
#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include <charconv>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "canopen/eds/eds.hpp"
#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/link_monitor.hpp"
#include "sim/simulator.hpp"

namespace {

struct UsageError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

constexpr const char* kUsage =
    "usage: canopen-sim --can IFACE --node N=EDSFILE [--node ...] [--heartbeat MS]\n"
    "                   [--tpdo-period MS] [--emcy-period MS] [--sync-period MS] [--auto-start]";

// --help; also the body of the installed manual page (cmake/packaging.cmake).
constexpr const char* kHelp = R"(
Simulated CANopen devices on a SocketCAN interface, for trying a master (such
as canopen-gateway) without hardware. Each node boots up, sends its heartbeat,
answers SDOs over its whole dictionary and NMT, and while operational changes
the values its TPDOs map. One line per event goes to stdout ("ready" once the
interface is open).

  --can IFACE        SocketCAN interface (vcan0, can0, ...). Required.
  --node N=EDSFILE   a device with node-ID N (1..127) described by EDSFILE
                     (EDS or DCF); repeatable, at least one. N = ff: the
                     device starts unconfigured (CiA 305 LSS, node-ID FFh):
                     no boot-up, no heartbeat, only LSS answers, until an
                     LSS master gives it a node-ID and switches it back to
                     waiting; then it boots with that node-ID ("lss ...:
                     node-ID N", "node N boot-up"). Several may be ff.
                     Every device is an LSS slave; its LSS address is its
                     1018h, with serial number 53000000h + N (55000000h +
                     k for the k-th unconfigured one) when the EDS gives 0.
                     A node-ID set by LSS on a configured device takes
                     effect at its next NMT reset communication.
  --heartbeat MS     every node's heartbeat period (1017h); 0: none.
                     Default: 1000.
  --tpdo-period MS   how often the mapped values change; 0: never.
                     Default: 100.
  --emcy-period MS   an EMCY every MS (raised, reset at the next); 0: none.
                     Default: 0.
  --sync-period MS   the first node also produces SYNC every MS, so
                     synchronous TPDOs flow; 0: no SYNC. Default: 0.
  --auto-start       go operational after boot-up without an NMT start.
  -h, --help         print this text and exit.

Exit status: 0 after SIGINT or SIGTERM; 2 for a bad command line or EDS file;
3 when the CAN interface cannot be opened.
)";

unsigned long number(std::string_view what, std::string_view s, unsigned long max) {
  unsigned long v = 0;
  int base = 10;
  if (s.starts_with("0x") || s.starts_with("0X")) {
    base = 16;
    s.remove_prefix(2);
  }
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, base);
  if (s.empty() || ec != std::errc() || p != s.data() + s.size() || v > max)
    throw UsageError(std::string(what) + ": bad value '" + std::string(s) + "'");
  return v;
}

// --node ff=...: a device that waits for LSS.
constexpr unsigned long kUnconfigured = 0xFF;

struct Args {
  bool help = false;
  std::string iface;
  std::vector<std::pair<std::uint8_t, std::string>> nodes;
  canopen::sim::SimulatorOptions options;
};

Args parse(const std::vector<std::string>& a) {
  Args out;
  for (std::size_t i = 0; i < a.size(); ++i) {
    auto value = [&]() -> const std::string& {
      if (i + 1 >= a.size()) throw UsageError(a[i] + ": missing value");
      return a[++i];
    };
    const std::string& opt = a[i];
    if (opt == "--can") {
      out.iface = value();
    } else if (opt == "--node") {
      const std::string& v = value();
      const auto eq = v.find('=');
      if (eq == std::string::npos || eq + 1 == v.size()) throw UsageError("--node: expected N=EDSFILE, got '" + v + "'");
      const std::string_view id_text = std::string_view(v).substr(0, eq);
      const auto n = id_text == "ff" || id_text == "FF" ? kUnconfigured : number("--node", id_text, 127);
      if (n < 1) throw UsageError("--node: node-ID must be 1..127 or ff");
      for (const auto& [id, f] : out.nodes)
        if (id == n && n != kUnconfigured) throw UsageError("--node: node " + std::to_string(n) + " given twice");
      out.nodes.emplace_back(static_cast<std::uint8_t>(n), v.substr(eq + 1));
    } else if (opt == "--heartbeat") {
      out.options.heartbeat = std::chrono::milliseconds(number(opt, value(), 65535));
    } else if (opt == "--tpdo-period") {
      out.options.tpdo_period = std::chrono::milliseconds(number(opt, value(), 3'600'000));
    } else if (opt == "--emcy-period") {
      out.options.emcy_period = std::chrono::milliseconds(number(opt, value(), 3'600'000));
    } else if (opt == "--sync-period") {
      out.options.sync_period = std::chrono::milliseconds(number(opt, value(), 4'294'967));
    } else if (opt == "--auto-start") {
      out.options.auto_start = true;
    } else if (opt == "--help" || opt == "-h") {
      out.help = true;
      return out;
    } else {
      throw UsageError("unknown option '" + opt + "'");
    }
  }
  if (out.iface.empty()) throw UsageError("--can IFACE is required");
  if (out.nodes.empty()) throw UsageError("at least one --node N=EDSFILE is required");
  return out;
}

void say(std::string_view line) {
  std::fwrite(line.data(), 1, line.size(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
}

int fail(int status, const std::string& msg) {
  std::fprintf(stderr, "canopen-sim: error: %s\n", msg.c_str());
  return status;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = parse(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const UsageError& e) {
    return fail(2, e.what());
  }
  if (args.help) {
    std::printf("%s\n%s", kUsage, kHelp);
    return 0;
  }
  // EDS files first: a bad file is refused before touching the bus.
  try {
    for (const auto& [node, file] : args.nodes)
      (void)canopen::eds::load_device_description(file, node == kUnconfigured ? 1 : node);
  } catch (const canopen::eds::EdsError& e) {
    return fail(2, e.what());
  }

  try {
    boost::asio::io_context io;
    auto monitor = canopen::socketcan::LinkMonitor::create(io);
    auto channel = canopen::socketcan::SocketCanChannel::open(io, args.iface, monitor);
    canopen::sim::Simulator sim(io, *channel, args.options, say);
    // From the files (checked above), so a node-ID set by LSS reloads them at the new node-ID.
    for (const auto& [node, file] : args.nodes) {
      if (node == kUnconfigured) sim.add_unconfigured_node(std::filesystem::path(file));
      else sim.add_node(node, std::filesystem::path(file));
    }
    boost::asio::signal_set signals(io, SIGINT, SIGTERM);
    signals.async_wait([&](const boost::system::error_code&, int) {
      sim.stop();
      channel->close();
      monitor->stop();
    });
    say("ready");
    sim.start();
    io.run();
  } catch (const canopen::socketcan::CanUnavailable& e) {
    return fail(3, e.what());
  } catch (const std::exception& e) {
    return fail(2, e.what());
  }
  return 0;
}
