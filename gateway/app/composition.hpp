// The composition root: turns the configuration into one NetworkUnit per
// network. It loads every node's EDS/DCF, opens each network's channel -
// SocketCAN (with one link monitor shared by all), or for a simulated
// network the in-process bus with its simulated devices on the other end,
// handed to the unit the same way, as a can::Channel - and builds the unit.
// main() calls it and hands the result to the App.
//
// Thread safety: call on the io_context's thread, before it runs.
#pragma once

#include <memory>
#include <vector>

#include <boost/asio/io_context.hpp>

#include "config/config.hpp"
#include "log.hpp"
#include "app/network_unit.hpp"

namespace canopen::socketcan {
class LinkMonitor;
}

namespace gateway {

struct Composition {
  Composition();
  Composition(Composition&&) noexcept;
  Composition& operator=(Composition&&) noexcept;
  ~Composition();

  // Interface up/down for the SocketCAN networks; nullptr when none is real.
  std::shared_ptr<canopen::socketcan::LinkMonitor> monitor;
  // config.networks[i] is units[i], number i + 1.
  std::vector<std::unique_ptr<NetworkUnit>> units;
};

// Throws ConfigError for a bad EDS/DCF ("file:line: reason") or a value
// the own dictionary refuses, and socketcan::CanUnavailable when an
// interface cannot be opened: configuration problems surface before
// anything starts.
Composition compose_networks(boost::asio::io_context& io, const Config& config, Logger& log);

}  // namespace gateway
