// LSS slave (CiA 305) for simulated devices: the two states (waiting,
// configuration), the pending and the active node-ID, and the slave side of
// every service: switch state global/selective, configure node-ID and bit
// timing, activate bit timing, store, inquire identity/node-ID, identify
// remote slave, identify non-configured slave and fastscan.
//
// Node-IDs, as CiA 305 has them (facts C.1, C.4 item 1): configure node-ID
// sets the PENDING node-ID; it becomes the ACTIVE one at the next NMT reset
// communication (the device calls reset_communication() and uses what it
// returns). A device without an active node-ID (FFh, "unconfigured") that
// leaves configuration state with a valid pending node-ID resets
// communication by itself: on_activate(node) tells the device to boot with
// it. Fastscan and identify non-configured are answered only by a slave in
// waiting state whose pending and active node-IDs are both FFh.
//
// The caller MUST pass every received frame to on_frame() (only 7E5h is
// used). No timers: activate bit timing's delay is the device's business.
//
// Thread safety: none; use from one thread. Callbacks and the sink run
// synchronously inside on_frame() and must not call back into the slave.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "canopen/can/frame.hpp"
#include "canopen/lss/frames.hpp"

namespace canopen::lss {

struct SlaveCallbacks {
  // Store configuration (cs 17h): persist pending node-ID and bit timing.
  // Returns the CiA 305 answer: 0 ok, 1 not supported, 2 storage media
  // access error, FFh manufacturer-specific. Unset: 1 (not supported).
  std::function<std::uint8_t(std::uint8_t pending_node_id, std::optional<std::uint8_t> bit_timing_index)> store;
  // Configure bit timing (cs 13h): whether the device supports the table
  // and index. Unset: table 0 with an index that has a bit rate.
  std::function<bool(std::uint8_t table, std::uint8_t index)> bit_timing_supported;
  // Activate bit timing (cs 15h) with the switch delay in ms.
  std::function<void(std::uint16_t switch_delay_ms)> activate_bit_timing;
  // An unconfigured device got its node-ID (see top): reset communication
  // and boot with it. The slave's active node-ID already is `node_id`.
  std::function<void(std::uint8_t node_id)> on_activate;
};

class LssSlave {
 public:
  // node_id: the stored node-ID at power-on, 1..127 or FFh (unconfigured);
  // it is both the pending and the active one.
  LssSlave(Identity identity, std::uint8_t node_id, FrameSink sink, SlaveCallbacks callbacks = {});

  // Returns true when the frame was an LSS master frame (7E5h).
  bool on_frame(const can::Frame& frame);

  // NMT reset communication of the device: the pending node-ID becomes the
  // active one, which is returned (FFh: the device has none and must stay
  // silent apart from LSS).
  std::uint8_t reset_communication();

  Mode mode() const { return mode_; }
  std::uint8_t active_node_id() const { return active_; }
  std::uint8_t pending_node_id() const { return pending_; }
  const Identity& identity() const { return identity_; }
  bool unconfigured() const { return active_ == kUnconfiguredNodeId && pending_ == kUnconfiguredNodeId; }
  // The table-0 index set by configure bit timing, if any.
  std::optional<std::uint8_t> pending_bit_timing() const { return bit_timing_; }

 private:
  // Where switch state selective's four frames have got to.
  enum class SelectiveStep : std::uint8_t { ExpectVendor, ExpectProduct, ExpectRevision, ExpectSerial };
  // Where identify remote slave's six frames have got to.
  enum class IdentifyStep : std::uint8_t {
    ExpectVendor, ExpectProduct, ExpectRevisionLow, ExpectRevisionHigh, ExpectSerialLow, ExpectSerialHigh
  };

  void on_switch_global(const can::Frame& f);
  void on_switch_selective(const can::Frame& f);
  void on_identify_remote(const can::Frame& f);
  void on_fastscan(const can::Frame& f);
  void on_configuration_service(const can::Frame& f);
  void enter_waiting();
  void send(const can::Frame& f) { if (sink_) sink_(f); }

  Identity identity_;
  std::uint8_t active_;
  std::uint8_t pending_;
  std::optional<std::uint8_t> bit_timing_;
  Mode mode_ = Mode::Waiting;
  FrameSink sink_;
  SlaveCallbacks callbacks_;
  SelectiveStep selective_ = SelectiveStep::ExpectVendor;
  IdentifyStep identify_ = IdentifyStep::ExpectVendor;
  bool identify_match_ = true;  // every identify frame so far was in range
  Part fastscan_position_ = Part::Vendor;
};

}  // namespace canopen::lss
