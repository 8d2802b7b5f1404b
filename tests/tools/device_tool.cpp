// device_tool: a CANopen device built from the stack over real SocketCAN, for
// the system tests (the gateway as NMT master on one side of a vcan bus, this
// process as a remote node on the other).
//
//   device_tool IFACE NODE EDSFILE [--heartbeat MS] [--emcy-after MS CODE] [--tpdo-period MS]
//
// A canopen::Device on the dictionary of EDSFILE (with $NODEID = NODE). It sends
// its boot-up message, heartbeats every MS (1017h), serves SDO, raises EMCY
// CODE once MS after start, and every --tpdo-period increments the first
// integer mapped into TPDO 1 (an object write: the TPDOs mapping it are
// events), but only while operational (CiA 301 7.3.2.2.5: PDOs only in that
// state).
// Prints "ready", NMT state changes, "emcy CODE" and "tpdo VALUE" on stdout.
// SIGINT/SIGTERM: exit 0.
#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>

#include <chrono>
#include <cstdio>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "canopen/device.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/link_monitor.hpp"
#include "canopen/socketcan/service_driver.hpp"
#include "tool_support.hpp"

namespace {

using canopen::tools::parse_number;

// The first integer object mapped into TPDO 1 (1A00h), if any.
std::optional<std::pair<std::uint16_t, std::uint8_t>> first_mapped_integer(const canopen::od::ObjectDictionary& od) {
  const auto count = od.get_unsigned(0x1A00, 0).value_or(0);
  for (std::uint8_t i = 1; i <= count && i != 0; ++i) {
    const auto entry = od.get_unsigned(0x1A00, i).value_or(0);
    const auto index = static_cast<std::uint16_t>(entry >> 16);
    const auto sub = static_cast<std::uint8_t>((entry >> 8) & 0xFF);
    auto v = od.get(index, sub);
    if (v && (canopen::is_signed_integer(v->type) || canopen::is_unsigned_integer(v->type))) {
      return std::pair{index, sub};
    }
  }
  return std::nullopt;
}

// v + 1, wrapping within its type.
canopen::Value incremented(const canopen::Value& v) {
  if (const auto* u = std::get_if<std::uint64_t>(&v.data)) {
    return canopen::Value::of_unsigned(v.type, *u >= canopen::unsigned_max(v.type) ? 0 : *u + 1);
  }
  const auto s = std::get<std::int64_t>(v.data);
  return canopen::Value::of_signed(v.type, s >= canopen::signed_max(v.type) ? canopen::signed_min(v.type) : s + 1);
}

void say(const std::string& line) {
  std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

int run(const std::vector<std::string>& a) {
  if (a.size() < 3) throw std::invalid_argument("usage: device_tool IFACE NODE EDSFILE [--heartbeat MS] "
                                                "[--emcy-after MS CODE] [--tpdo-period MS]");
  const std::string iface = a[0];
  const auto node_number = parse_number(a[1]);
  if (node_number < 1 || node_number > 127) throw std::invalid_argument("NODE must be 1..127");
  const auto node = static_cast<std::uint8_t>(node_number);
  std::optional<unsigned long> heartbeat_ms, emcy_after_ms, tpdo_period_ms;
  std::uint16_t emcy_code = 0;
  for (std::size_t i = 3; i < a.size(); ++i) {
    auto value = [&]() -> unsigned long {
      if (i + 1 >= a.size()) throw std::invalid_argument(a[i] + ": missing value");
      return parse_number(a[++i]);
    };
    if (a[i] == "--heartbeat") {
      heartbeat_ms = value();
    } else if (a[i] == "--emcy-after") {
      emcy_after_ms = value();
      emcy_code = static_cast<std::uint16_t>(value());
    } else if (a[i] == "--tpdo-period") {
      tpdo_period_ms = value();
    } else {
      throw std::invalid_argument("unknown option " + a[i]);
    }
  }

  auto desc = canopen::eds::load_device_description(a[2], node);
  auto& od = desc.od;
  if (heartbeat_ms) {
    // Set before start(): the NMT slave reads 1017h during its initialisation.
    if (auto ec = od.set(0x1017, 0, canopen::Value::of_unsigned(canopen::DataType::Unsigned16, *heartbeat_ms)))
      throw std::runtime_error("cannot set 1017h: " + ec.message());
  }

  boost::asio::io_context io;
  auto monitor = canopen::socketcan::LinkMonitor::create(io);
  auto channel = canopen::socketcan::SocketCanChannel::open(io, iface, monitor);

  canopen::DeviceConfig cfg;
  cfg.node_id = node;
  canopen::DeviceCallbacks callbacks;
  callbacks.on_state_change = [](canopen::NmtState now, canopen::NmtState) {
    say("state " + std::string(canopen::to_string(now)));
  };
  canopen::Device device(od, cfg, [&channel](const canopen::can::Frame& f) { channel->send(f); }, callbacks);
  if (!device.pdo_errors().empty()) throw std::runtime_error(device.pdo_errors().front());
  const auto counter = first_mapped_integer(od);

  canopen::socketcan::ServiceDriver driver(io, *channel);
  driver.add(device);
  device.start(canopen::SteadyClock::now());  // boot-up (7.2.8.3.3), then heartbeats

  boost::asio::steady_timer emcy_timer(io);
  if (emcy_after_ms) {
    emcy_timer.expires_after(std::chrono::milliseconds(*emcy_after_ms));
    emcy_timer.async_wait([&](const boost::system::error_code& ec) {
      if (ec) return;
      char code[8];
      std::snprintf(code, sizeof code, "%04X", emcy_code);
      if (device.raise_emcy(emcy_code, 0, canopen::SteadyClock::now())) say(std::string("emcy ") + code);
    });
  }

  boost::asio::steady_timer tpdo_timer(io);
  std::function<void()> tpdo_tick = [&] {
    tpdo_timer.expires_after(std::chrono::milliseconds(*tpdo_period_ms));
    tpdo_timer.async_wait([&](const boost::system::error_code& ec) {
      if (ec) return;
      if (counter && device.state() == canopen::NmtState::Operational) {
        const auto [index, sub] = *counter;
        if (auto v = od.get(index, sub)) {
          const auto next = incremented(*v);
          if (!device.set(index, sub, next, canopen::SteadyClock::now())) say("tpdo " + canopen::format_value(next));
        }
      }
      tpdo_tick();
    });
  };
  if (tpdo_period_ms && *tpdo_period_ms > 0) tpdo_tick();

  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) {
    emcy_timer.cancel();
    tpdo_timer.cancel();
    driver.remove(&device);
    channel->close();
    monitor->stop();
  });
  say("ready");
  io.run();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "device_tool: %s\n", e.what());
    return 2;
  }
}
