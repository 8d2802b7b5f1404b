// LSS wire format (CiA 305; facts C.1): the two COB-IDs, the command
// specifiers of every service, the 128-bit LSS address (the four 1018h
// values) and builders/parsers of each frame in both directions.
//
// Every LSS frame has exactly 8 data bytes, unused bytes 0. Byte 0 is the
// command specifier (cs); multi-byte values are little-endian. A received
// frame is an LSS frame only with the right COB-ID, an 11-bit id, no RTR,
// no FD and DLC 8 (is_master_frame / is_slave_frame); anything else is
// ignored by both sides, as CANopenNode's slave does.
//
// All functions are pure and thread-safe.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "canopen/can/frame.hpp"

namespace canopen::lss {

// Where the LSS services put the frames they send.
using FrameSink = std::function<void(const can::Frame&)>;

inline constexpr std::uint32_t kMasterCobId = 0x7E5;  // master -> slaves
inline constexpr std::uint32_t kSlaveCobId = 0x7E4;   // slaves -> master
inline constexpr std::size_t kFrameLength = 8;
// The node-ID of an unconfigured device, and the value that unconfigures
// one in configure node-ID.
inline constexpr std::uint8_t kUnconfiguredNodeId = 0xFF;

// Command specifiers (byte 0), CiA 305; facts C.1.
namespace cs {
inline constexpr std::uint8_t SwitchStateGlobal = 0x04;       // unconfirmed
inline constexpr std::uint8_t ConfigureNodeId = 0x11;         // answered with the same cs
inline constexpr std::uint8_t ConfigureBitTiming = 0x13;      // answered with the same cs
inline constexpr std::uint8_t ActivateBitTiming = 0x15;       // unconfirmed
inline constexpr std::uint8_t StoreConfiguration = 0x17;      // answered with the same cs
inline constexpr std::uint8_t SwitchSelectiveVendor = 0x40;   // + Part: 40h..43h
inline constexpr std::uint8_t SwitchSelectiveResponse = 0x44;
inline constexpr std::uint8_t IdentifyVendor = 0x46;          // identify remote slave, 46h..4Bh
inline constexpr std::uint8_t IdentifyProduct = 0x47;
inline constexpr std::uint8_t IdentifyRevisionLow = 0x48;
inline constexpr std::uint8_t IdentifyRevisionHigh = 0x49;
inline constexpr std::uint8_t IdentifySerialLow = 0x4A;
inline constexpr std::uint8_t IdentifySerialHigh = 0x4B;
inline constexpr std::uint8_t IdentifyNonConfigured = 0x4C;
inline constexpr std::uint8_t IdentifySlave = 0x4F;           // answer to 46h..4Bh and to fastscan
inline constexpr std::uint8_t IdentifyNonConfiguredSlave = 0x50;
inline constexpr std::uint8_t Fastscan = 0x51;
inline constexpr std::uint8_t InquireVendor = 0x5A;           // + Part: 5Ah..5Dh, answered with the same cs
inline constexpr std::uint8_t InquireNodeId = 0x5E;
}  // namespace cs

// Fastscan BitChecked value that resets every unconfigured slave's scan
// and makes it answer (facts C.2 step 1).
inline constexpr std::uint8_t kFastscanReset = 0x80;

// The four parts of the LSS address, in fastscan's LSSSub/LSSNext numbering.
enum class Part : std::uint8_t { Vendor = 0, Product = 1, Revision = 2, Serial = 3 };

// The LSS address: the device's 1018h sub 1..4.
struct Identity {
  std::uint32_t vendor_id = 0;
  std::uint32_t product_code = 0;
  std::uint32_t revision = 0;
  std::uint32_t serial = 0;

  std::uint32_t part(Part p) const;
  void set_part(Part p, std::uint32_t value);
  friend bool operator==(const Identity&, const Identity&) = default;
  // Lexicographic (vendor, product, revision, serial): fastscan finds the
  // lowest unconfigured identity first.
  friend auto operator<=>(const Identity&, const Identity&) = default;
};
// "vendor 0x00000123 product 0x... revision 0x... serial 0x..." for logs and details.
std::string to_string(const Identity& id);

// Identify remote slave's range (CiA 305): vendor and product exact,
// revision and serial each within [low, high].
struct IdentityRange {
  std::uint32_t vendor_id = 0;
  std::uint32_t product_code = 0;
  std::uint32_t revision_low = 0;
  std::uint32_t revision_high = 0xFFFFFFFF;
  std::uint32_t serial_low = 0;
  std::uint32_t serial_high = 0xFFFFFFFF;
  bool contains(const Identity& id) const;
};

// The LSS slave's two states (CiA 305); switch state global's byte 1.
enum class Mode : std::uint8_t { Waiting = 0, Configuration = 1 };

// Bit timing table 0 (the CiA 301 bit rates), index -> bit rate in bit/s;
// index 5 is reserved, 9 is automatic bit rate detection.
inline constexpr std::uint8_t kBitTimingTableCia = 0;
inline constexpr std::uint8_t kBitTimingAuto = 9;
// The table-0 index of a bit rate; nullopt for rates the table lacks.
std::optional<std::uint8_t> bit_timing_index(std::uint32_t bit_rate);
// The bit rate of a table-0 index; nullopt for 5 (reserved), 9 (auto) and above.
std::optional<std::uint32_t> bit_rate_of_index(std::uint8_t index);

// A fastscan request (cs 51h): bytes 1..4 IDNumber, 5 BitChecked, 6 LSSSub, 7 LSSNext.
struct FastscanFields {
  std::uint32_t id_number = 0;
  std::uint8_t bit_checked = 0;  // 0..31, or kFastscanReset
  std::uint8_t sub = 0;          // Part being checked
  std::uint8_t next = 0;         // Part the matching slaves move to
  friend bool operator==(const FastscanFields&, const FastscanFields&) = default;
};

// ---- Builders: master -> slaves (COB-ID 7E5h) ----
can::Frame switch_state_global(Mode mode);
// One of the four frames of switch state selective (cs 40h + part).
can::Frame switch_state_selective(Part part, std::uint32_t value);
can::Frame configure_node_id(std::uint8_t node_id);
can::Frame configure_bit_timing(std::uint8_t table, std::uint8_t index);
can::Frame activate_bit_timing(std::uint16_t switch_delay_ms);
can::Frame store_configuration();
can::Frame inquire_identity(Part part);
can::Frame inquire_node_id();
// One of the six frames of identify remote slave (cs 46h..4Bh).
can::Frame identify_remote_slave(std::uint8_t command, std::uint32_t value);
can::Frame identify_non_configured();
can::Frame fastscan(const FastscanFields& f);

// ---- Builders: slave -> master (COB-ID 7E4h) ----
can::Frame switch_state_selective_response();
// error: 0 ok, else the service's CiA 305 code; specific: byte 2 when error is FFh.
can::Frame configure_response(std::uint8_t command, std::uint8_t error, std::uint8_t specific = 0);
can::Frame inquire_identity_response(Part part, std::uint32_t value);
can::Frame inquire_node_id_response(std::uint8_t node_id);
can::Frame identify_slave_response();
can::Frame identify_non_configured_response();

// ---- Parsers ----
// True for a well-formed frame on the master's / the slaves' COB-ID (see top).
bool is_master_frame(const can::Frame& f);
bool is_slave_frame(const can::Frame& f);
inline std::uint8_t command(const can::Frame& f) { return f.data[0]; }
// The uint32 in bytes 1..4.
std::uint32_t u32(const can::Frame& f);
FastscanFields fastscan_fields(const can::Frame& f);

}  // namespace canopen::lss
