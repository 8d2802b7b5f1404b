#include "canopen/lss/frames.hpp"

#include <array>
#include <cstdio>

namespace canopen::lss {

namespace {

using Payload = std::array<std::uint8_t, kFrameLength>;

can::Frame make(std::uint32_t id, const Payload& p) { return can::Frame::standard(id, p); }

Payload with_u32(std::uint8_t command, std::uint32_t v) {
  return {command,
          static_cast<std::uint8_t>(v),
          static_cast<std::uint8_t>(v >> 8),
          static_cast<std::uint8_t>(v >> 16),
          static_cast<std::uint8_t>(v >> 24),
          0,
          0,
          0};
}

bool well_formed(const can::Frame& f, std::uint32_t id) {
  return f.id == id && !f.extended() && !f.remote() && !f.fd() && f.len == kFrameLength;
}

// CiA 305 bit timing table 0 (CiA 301 bit rates); 0 marks reserved/auto.
constexpr std::array<std::uint32_t, 10> kTable0{1'000'000, 800'000, 500'000, 250'000, 125'000,
                                                0,         50'000,  20'000,  10'000,  0};

}  // namespace

std::uint32_t Identity::part(Part p) const {
  switch (p) {
    case Part::Vendor: return vendor_id;
    case Part::Product: return product_code;
    case Part::Revision: return revision;
    case Part::Serial: return serial;
  }
  return 0;
}

void Identity::set_part(Part p, std::uint32_t value) {
  switch (p) {
    case Part::Vendor: vendor_id = value; break;
    case Part::Product: product_code = value; break;
    case Part::Revision: revision = value; break;
    case Part::Serial: serial = value; break;
  }
}

std::string to_string(const Identity& id) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "vendor 0x%08X product 0x%08X revision 0x%08X serial 0x%08X", id.vendor_id,
                id.product_code, id.revision, id.serial);
  return buf;
}

bool IdentityRange::contains(const Identity& id) const {
  return id.vendor_id == vendor_id && id.product_code == product_code && id.revision >= revision_low &&
         id.revision <= revision_high && id.serial >= serial_low && id.serial <= serial_high;
}

std::optional<std::uint8_t> bit_timing_index(std::uint32_t bit_rate) {
  if (bit_rate == 0) return std::nullopt;
  for (std::size_t i = 0; i < kTable0.size(); ++i)
    if (kTable0[i] == bit_rate) return static_cast<std::uint8_t>(i);
  return std::nullopt;
}

std::optional<std::uint32_t> bit_rate_of_index(std::uint8_t index) {
  if (index >= kTable0.size() || kTable0[index] == 0) return std::nullopt;
  return kTable0[index];
}

can::Frame switch_state_global(Mode mode) {
  return make(kMasterCobId, {cs::SwitchStateGlobal, static_cast<std::uint8_t>(mode), 0, 0, 0, 0, 0, 0});
}

can::Frame switch_state_selective(Part part, std::uint32_t value) {
  return make(kMasterCobId, with_u32(static_cast<std::uint8_t>(cs::SwitchSelectiveVendor + static_cast<int>(part)), value));
}

can::Frame configure_node_id(std::uint8_t node_id) {
  return make(kMasterCobId, {cs::ConfigureNodeId, node_id, 0, 0, 0, 0, 0, 0});
}

can::Frame configure_bit_timing(std::uint8_t table, std::uint8_t index) {
  return make(kMasterCobId, {cs::ConfigureBitTiming, table, index, 0, 0, 0, 0, 0});
}

can::Frame activate_bit_timing(std::uint16_t switch_delay_ms) {
  return make(kMasterCobId, {cs::ActivateBitTiming, static_cast<std::uint8_t>(switch_delay_ms),
                             static_cast<std::uint8_t>(switch_delay_ms >> 8), 0, 0, 0, 0, 0});
}

can::Frame store_configuration() { return make(kMasterCobId, {cs::StoreConfiguration, 0, 0, 0, 0, 0, 0, 0}); }

can::Frame inquire_identity(Part part) {
  return make(kMasterCobId,
              {static_cast<std::uint8_t>(cs::InquireVendor + static_cast<int>(part)), 0, 0, 0, 0, 0, 0, 0});
}

can::Frame inquire_node_id() { return make(kMasterCobId, {cs::InquireNodeId, 0, 0, 0, 0, 0, 0, 0}); }

can::Frame identify_remote_slave(std::uint8_t command, std::uint32_t value) {
  return make(kMasterCobId, with_u32(command, value));
}

can::Frame identify_non_configured() {
  return make(kMasterCobId, {cs::IdentifyNonConfigured, 0, 0, 0, 0, 0, 0, 0});
}

can::Frame fastscan(const FastscanFields& f) {
  Payload p = with_u32(cs::Fastscan, f.id_number);
  p[5] = f.bit_checked;
  p[6] = f.sub;
  p[7] = f.next;
  return make(kMasterCobId, p);
}

can::Frame switch_state_selective_response() {
  return make(kSlaveCobId, {cs::SwitchSelectiveResponse, 0, 0, 0, 0, 0, 0, 0});
}

can::Frame configure_response(std::uint8_t command, std::uint8_t error, std::uint8_t specific) {
  return make(kSlaveCobId, {command, error, error == 0xFF ? specific : std::uint8_t{0}, 0, 0, 0, 0, 0});
}

can::Frame inquire_identity_response(Part part, std::uint32_t value) {
  return make(kSlaveCobId, with_u32(static_cast<std::uint8_t>(cs::InquireVendor + static_cast<int>(part)), value));
}

can::Frame inquire_node_id_response(std::uint8_t node_id) {
  return make(kSlaveCobId, {cs::InquireNodeId, node_id, 0, 0, 0, 0, 0, 0});
}

can::Frame identify_slave_response() { return make(kSlaveCobId, {cs::IdentifySlave, 0, 0, 0, 0, 0, 0, 0}); }

can::Frame identify_non_configured_response() {
  return make(kSlaveCobId, {cs::IdentifyNonConfiguredSlave, 0, 0, 0, 0, 0, 0, 0});
}

bool is_master_frame(const can::Frame& f) { return well_formed(f, kMasterCobId); }
bool is_slave_frame(const can::Frame& f) { return well_formed(f, kSlaveCobId); }

std::uint32_t u32(const can::Frame& f) {
  return static_cast<std::uint32_t>(f.data[1]) | (static_cast<std::uint32_t>(f.data[2]) << 8) |
         (static_cast<std::uint32_t>(f.data[3]) << 16) | (static_cast<std::uint32_t>(f.data[4]) << 24);
}

FastscanFields fastscan_fields(const can::Frame& f) { return {u32(f), f.data[5], f.data[6], f.data[7]}; }

}  // namespace canopen::lss
