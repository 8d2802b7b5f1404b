// Helpers shared by the LSS tests: frames as their can-utils text
// ("7E5#0401000000000000") so expectations read like a candump, and an
// in-memory bus with one LssMaster and any number of LssSlaves on a fake
// clock.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/can/memory_bus.hpp"
#include "canopen/clock.hpp"
#include "canopen/lss/master.hpp"
#include "canopen/lss/slave.hpp"
#include "support/frames.hpp"

namespace canopen::lss::test {

using canopen::test::FrameLog;
using canopen::test::parse;

// One master and the slaves on a MemoryBus; time only moves in run().
struct LssBus {
  explicit LssBus(MasterConfig config = {}) : master(config, [this](const can::Frame& f) { master_ep->send(f); }) {
    master_ep->on_frames([this](std::span<const can::Frame> frames) {
      for (const auto& f : frames) master.on_frame(f, clock.now());
    });
  }

  struct Node {
    std::unique_ptr<can::MemoryEndpoint> ep;
    std::unique_ptr<LssSlave> slave;
    std::vector<std::uint8_t> activated;  // node-IDs on_activate gave
    std::uint8_t stored = kUnconfiguredNodeId;
  };

  Node& add_slave(const Identity& identity, std::uint8_t stored_node_id = kUnconfiguredNodeId) {
    auto n = std::make_unique<Node>();
    n->ep = bus.attach("slave" + std::to_string(nodes.size()));
    Node* raw = n.get();
    SlaveCallbacks cb;
    cb.on_activate = [raw](std::uint8_t node_id) { raw->activated.push_back(node_id); };
    cb.store = [raw](std::uint8_t pending, std::optional<std::uint8_t>) {
      raw->stored = pending;
      return std::uint8_t{0};
    };
    n->slave = std::make_unique<LssSlave>(identity, stored_node_id, [raw](const can::Frame& f) { raw->ep->send(f); }, cb);
    n->ep->on_frames([raw](std::span<const can::Frame> frames) {
      for (const auto& f : frames) raw->slave->on_frame(f);
    });
    nodes.push_back(std::move(n));
    return *raw;
  }

  // Delivers frames and moves the clock to each deadline of the master
  // until it is idle. Returns how many step windows (timer expiries) passed.
  std::size_t run() {
    std::size_t expiries = 0;
    for (;;) {
      bus.deliver();
      if (!master.busy()) return expiries;
      const TimePoint next = master.next_deadline();
      if (next == TimePoint::max()) return expiries;  // waits for a frame that never comes
      clock.advance_to(next);
      master.on_time(clock.now());
      ++expiries;
    }
  }

  FakeClock clock;
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> master_ep = bus.attach("master");
  LssMaster master;
  std::vector<std::unique_ptr<Node>> nodes;
};

}  // namespace canopen::lss::test
