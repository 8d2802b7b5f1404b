// An output that takes the stack's events typed (canopen::Event, before the
// pipeline encodes them) and runs its own session beside the App's: the
// Sparkplug B edge node (sparkplug/edge_node.hpp). The composition root
// makes one (app/front_ends.hpp) and hands it to the App (App::add_output),
// which
//   start()         calls after the MQTT output started, before the
//                   networks' first events (bus state, own boot-up);
//   on_event()      calls for every event of every network, before the
//                   event is encoded and published;
//   node_changed()  calls when a node's settings or EDS/DCF changed at run
//                   time (PUT .../config, .../eds, DELETE), with the settings
//                   that apply now (a node no longer configured: its id
//                   and nothing else);
//   stop()          calls while the networks still run, before the MQTT
//                   output stops (it may block the io thread briefly to
//                   send its last messages).
//
// Thread safety: every call on the App's io thread.
#pragma once

#include <cstdint>

#include "canopen/events.hpp"
#include "core/node_entry.hpp"

namespace gateway {

class StackOutput {
 public:
  virtual ~StackOutput() = default;
  virtual void start() = 0;
  virtual void on_event(std::uint32_t network, const canopen::Event& ev) = 0;
  virtual void node_changed(std::uint32_t network, const NodeConfig& node) = 0;
  virtual void stop() = 0;
};

}  // namespace gateway
