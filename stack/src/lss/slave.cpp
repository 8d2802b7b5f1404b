// The slave side of every LSS service (CiA 305; facts C.1, C.2).
#include "canopen/lss/slave.hpp"

namespace canopen::lss {

LssSlave::LssSlave(Identity identity, std::uint8_t node_id, FrameSink sink, SlaveCallbacks callbacks)
    : identity_(identity),
      active_(node_id),
      pending_(node_id),
      sink_(std::move(sink)),
      callbacks_(std::move(callbacks)) {}

bool LssSlave::on_frame(const can::Frame& f) {
  if (!is_master_frame(f)) return false;  // DLC != 8, RTR, other ids: not LSS
  const std::uint8_t c = command(f);
  if (c == cs::SwitchStateGlobal) {
    on_switch_global(f);
  } else if (c >= cs::SwitchSelectiveVendor && c <= cs::SwitchSelectiveVendor + 3) {
    on_switch_selective(f);
  } else if (c >= cs::IdentifyVendor && c <= cs::IdentifySerialHigh) {
    on_identify_remote(f);
  } else if (c == cs::IdentifyNonConfigured) {
    if (unconfigured()) send(identify_non_configured_response());
  } else if (c == cs::Fastscan) {
    on_fastscan(f);
  } else if (mode_ == Mode::Configuration) {
    on_configuration_service(f);
  }
  return true;
}

std::uint8_t LssSlave::reset_communication() {
  active_ = pending_;
  return active_;
}

void LssSlave::on_switch_global(const can::Frame& f) {
  if (f.data[1] == static_cast<std::uint8_t>(Mode::Waiting)) {
    enter_waiting();
  } else if (f.data[1] == static_cast<std::uint8_t>(Mode::Configuration)) {
    mode_ = Mode::Configuration;
  }
}

void LssSlave::enter_waiting() {
  const bool was_configuring = mode_ == Mode::Configuration;
  mode_ = Mode::Waiting;
  selective_ = SelectiveStep::ExpectVendor;
  // An unconfigured device that got a node-ID boots with it at once.
  if (was_configuring && active_ == kUnconfiguredNodeId && pending_ != kUnconfiguredNodeId) {
    active_ = pending_;
    if (callbacks_.on_activate) callbacks_.on_activate(active_);
  }
}

void LssSlave::on_switch_selective(const can::Frame& f) {
  if (mode_ != Mode::Waiting) return;
  const auto part = static_cast<Part>(command(f) - cs::SwitchSelectiveVendor);
  // The four frames must come in order; anything else starts over.
  if (part == Part::Vendor) selective_ = SelectiveStep::ExpectVendor;
  if (static_cast<std::uint8_t>(part) != static_cast<std::uint8_t>(selective_) || identity_.part(part) != u32(f)) {
    selective_ = SelectiveStep::ExpectVendor;
    return;
  }
  if (part != Part::Serial) {
    selective_ = static_cast<SelectiveStep>(static_cast<std::uint8_t>(selective_) + 1);
    return;
  }
  selective_ = SelectiveStep::ExpectVendor;
  mode_ = Mode::Configuration;
  send(switch_state_selective_response());
}

void LssSlave::on_identify_remote(const can::Frame& f) {
  const auto step = static_cast<IdentifyStep>(command(f) - cs::IdentifyVendor);
  if (step == IdentifyStep::ExpectVendor) {
    identify_ = IdentifyStep::ExpectVendor;
    identify_match_ = true;
  }
  if (step != identify_) {
    identify_ = IdentifyStep::ExpectVendor;
    return;
  }
  const std::uint32_t v = u32(f);
  bool in = true;
  switch (step) {
    case IdentifyStep::ExpectVendor: in = identity_.vendor_id == v; break;
    case IdentifyStep::ExpectProduct: in = identity_.product_code == v; break;
    case IdentifyStep::ExpectRevisionLow: in = identity_.revision >= v; break;
    case IdentifyStep::ExpectRevisionHigh: in = identity_.revision <= v; break;
    case IdentifyStep::ExpectSerialLow: in = identity_.serial >= v; break;
    case IdentifyStep::ExpectSerialHigh: in = identity_.serial <= v; break;
  }
  identify_match_ = identify_match_ && in;
  if (step != IdentifyStep::ExpectSerialHigh) {
    identify_ = static_cast<IdentifyStep>(static_cast<std::uint8_t>(step) + 1);
    return;
  }
  identify_ = IdentifyStep::ExpectVendor;
  if (identify_match_) send(identify_slave_response());
}

void LssSlave::on_fastscan(const can::Frame& f) {
  // Served only in waiting state by a device with neither a pending nor an
  // active node-ID (facts C.2 step 1, D.7).
  if (mode_ != Mode::Waiting || !unconfigured()) return;
  const FastscanFields fs = fastscan_fields(f);
  if ((fs.bit_checked > 31 && fs.bit_checked != kFastscanReset) || fs.sub > 3 || fs.next > 3) return;
  if (fs.bit_checked == kFastscanReset) {
    fastscan_position_ = Part::Vendor;
    send(identify_slave_response());
    return;
  }
  if (fs.sub != static_cast<std::uint8_t>(fastscan_position_)) return;
  const std::uint32_t mask = 0xFFFFFFFFU << fs.bit_checked;
  if ((identity_.part(fastscan_position_) & mask) != (fs.id_number & mask)) return;
  fastscan_position_ = static_cast<Part>(fs.next);
  // The last verify step: LSSNext < LSSSub means all parts matched.
  if (fs.bit_checked == 0 && fs.next < fs.sub) mode_ = Mode::Configuration;
  send(identify_slave_response());
}

void LssSlave::on_configuration_service(const can::Frame& f) {
  const std::uint8_t c = command(f);
  switch (c) {
    case cs::ConfigureNodeId: {
      const std::uint8_t id = f.data[1];
      const bool valid = (id >= 1 && id <= 127) || id == kUnconfiguredNodeId;
      if (valid) pending_ = id;
      send(configure_response(c, valid ? 0 : 1));
      return;
    }
    case cs::ConfigureBitTiming: {
      const std::uint8_t table = f.data[1], index = f.data[2];
      const bool ok = callbacks_.bit_timing_supported
                          ? callbacks_.bit_timing_supported(table, index)
                          : table == kBitTimingTableCia && bit_rate_of_index(index).has_value();
      if (ok) bit_timing_ = index;
      send(configure_response(c, ok ? 0 : 1));
      return;
    }
    case cs::ActivateBitTiming:
      if (callbacks_.activate_bit_timing)
        callbacks_.activate_bit_timing(static_cast<std::uint16_t>(f.data[1] | (f.data[2] << 8)));
      return;
    case cs::StoreConfiguration: {
      const std::uint8_t error = callbacks_.store ? callbacks_.store(pending_, bit_timing_) : std::uint8_t{1};
      send(configure_response(c, error));
      return;
    }
    case cs::InquireNodeId: send(inquire_node_id_response(active_)); return;
    default:
      if (c >= cs::InquireVendor && c <= cs::InquireVendor + 3) {
        const auto part = static_cast<Part>(c - cs::InquireVendor);
        send(inquire_identity_response(part, identity_.part(part)));
      }
      return;
  }
}

}  // namespace canopen::lss
