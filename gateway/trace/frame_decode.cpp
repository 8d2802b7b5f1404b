#include "trace/frame_decode.hpp"

#include "canopen/lss/frames.hpp"
#include "canopen/sdo/abort.hpp"
#include "core/format.hpp"

#include <cstdio>

namespace gateway::trace {

namespace {

using canopen::can::Frame;
using core::hex_number;

std::uint16_t u16(const Frame& f, std::size_t at) {
  return static_cast<std::uint16_t>(f.data[at] | f.data[at + 1] << 8);
}
std::uint32_t u32(const Frame& f, std::size_t at) {
  return static_cast<std::uint32_t>(f.data[at]) | static_cast<std::uint32_t>(f.data[at + 1]) << 8 |
         static_cast<std::uint32_t>(f.data[at + 2]) << 16 | static_cast<std::uint32_t>(f.data[at + 3]) << 24;
}

std::string node_text(std::uint8_t node) { return node == 0 ? "all" : std::to_string(node); }

// "1018h:01", the multiplexer of an SDO initiate/abort frame (bytes 1-3).
std::string mux(const Frame& f) { return core::index_text(u16(f, 1)) + ":" + hex_number(f.data[3], 2); }

std::string bytes(std::uint32_t n) { return std::to_string(n) + (n == 1 ? " byte" : " bytes"); }

// NMT node control (CiA 301 7.2.8.3.1): cs, node-ID (0 = all).
std::string nmt(const Frame& f) {
  if (f.len != 2) return "NMT malformed (" + bytes(f.len) + ")";
  const char* what = nullptr;
  switch (f.data[0]) {
    case 0x01: what = "start"; break;
    case 0x02: what = "stop"; break;
    case 0x80: what = "pre-operational"; break;
    case 0x81: what = "reset node"; break;
    case 0x82: what = "reset communication"; break;
    default: return "NMT cs " + hex_number(f.data[0], 2) + "h " + node_text(f.data[1]);
  }
  return std::string("NMT ") + what + " " + node_text(f.data[1]);
}

// TIME (7.2.6): 28 bits ms after midnight, 16 bits days since 1984-01-01.
std::string time_of_day(const Frame& f) {
  if (f.len != 6) return "TIME malformed (" + bytes(f.len) + ")";
  const std::uint32_t ms = u32(f, 0) & 0x0FFFFFFF;
  const std::uint32_t days = u16(f, 4);
  // Civil date from days since 1984-01-01 (= 5113 days after 1970-01-01).
  long z = static_cast<long>(days) + 5113 + 719468;
  const long era = z / 146097;
  const long doe = z - era * 146097;
  const long yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const long doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const long mp = (5 * doy + 2) / 153;
  const long d = doy - (153 * mp + 2) / 5 + 1;
  const long m = mp < 10 ? mp + 3 : mp - 9;
  const long y = yoe + era * 400 + (m <= 2 ? 1 : 0);
  char buf[64];
  std::snprintf(buf, sizeof buf, "TIME %04ld-%02ld-%02ld %02u:%02u:%02u.%03u", y, m, d, ms / 3600000,
                ms / 60000 % 60, ms / 1000 % 60, ms % 1000);
  return buf;
}

// EMCY (7.2.7.3.1): error code, error register, 5 manufacturer bytes.
std::string emcy(const Frame& f, std::uint8_t node) {
  std::string s = "EMCY " + std::to_string(node);
  if (f.len < 3) return s + " malformed (" + bytes(f.len) + ")";
  const std::uint16_t code = u16(f, 0);
  s += " " + hex_number(code, 4) + "h register " + hex_number(f.data[2], 2) + "h";
  if (code == 0) s += " (error reset)";
  return s;
}

// Heartbeat / boot-up / node guarding (7.2.8.3.2): state in bits 0-6,
// the guarding toggle in bit 7.
std::string error_control(const Frame& f, std::uint8_t node) {
  const std::string n = std::to_string(node);
  if (f.remote()) return "guard request " + n;
  if (f.len != 1) return "HB " + n + " malformed (" + bytes(f.len) + ")";
  const std::uint8_t state = f.data[0] & 0x7F;
  const std::string toggle = (f.data[0] & 0x80) ? " toggle" : "";
  switch (state) {
    case 0x00: return "boot-up " + n;
    case 0x04: return "HB " + n + " stopped" + toggle;
    case 0x05: return "HB " + n + " operational" + toggle;
    case 0x7F: return "HB " + n + " pre-operational" + toggle;
    default: return "HB " + n + " state " + hex_number(state, 2) + "h" + toggle;
  }
}

std::string abort_text(const Frame& f) {
  const std::uint32_t code = u32(f, 4);
  return "abort " + mux(f) + " " + core::abort_code_text(code) + " (" + std::string(canopen::sdo_abort_text(code)) +
         ")";
}

// Client -> server (600h+N), CiA 301 7.2.4.3: ccs in bits 5-7.
std::string sdo_request(const Frame& f, bool block_segment) {
  const std::uint8_t b0 = f.data[0];
  if (block_segment) return "block segment " + std::to_string(b0 & 0x7F) + ((b0 & 0x80) ? " last" : "");
  switch (b0 >> 5) {
    case 1: {  // initiate download
      std::string s = "download " + mux(f);
      if (b0 & 0x02) {  // expedited; size in n when s is set
        s += " " + bytes((b0 & 0x01) ? 4u - ((b0 >> 2) & 0x03) : 4u);
      } else if (b0 & 0x01) {
        s += " size " + std::to_string(u32(f, 4));
      }
      return s;
    }
    case 0: {  // download segment: n unused bytes in bits 1-3
      const unsigned n = 7u - ((b0 >> 1) & 0x07);
      return "download segment t" + std::to_string((b0 >> 4) & 1) + " " + bytes(n) + ((b0 & 0x01) ? " last" : "");
    }
    case 2: return "upload " + mux(f);
    case 3: return "upload segment t" + std::to_string((b0 >> 4) & 1);
    case 4: return abort_text(f);
    case 6:  // block download: cs in bit 0
      if ((b0 & 0x01) == 0)
        return "block download " + mux(f) + ((b0 & 0x02) ? " size " + std::to_string(u32(f, 4)) : "") +
               ((b0 & 0x04) ? " crc" : "");
      return "block download end " + bytes(7u - ((b0 >> 2) & 0x07)) + " crc " + hex_number(u16(f, 1), 4) + "h";
    case 5:  // block upload: cs in bits 0-1
      switch (b0 & 0x03) {
        case 0: return "block upload " + mux(f) + " blksize " + std::to_string(f.data[4]);
        case 3: return "block upload start";
        case 2: return "block upload ack seq " + std::to_string(f.data[1]) + " blksize " + std::to_string(f.data[2]);
        default: return "block upload end ok";
      }
    default: return "ccs " + std::to_string(b0 >> 5);
  }
}

// Server -> client (580h+N): scs in bits 5-7.
std::string sdo_response(const Frame& f, bool block_segment) {
  const std::uint8_t b0 = f.data[0];
  if (block_segment) return "block segment " + std::to_string(b0 & 0x7F) + ((b0 & 0x80) ? " last" : "");
  switch (b0 >> 5) {
    case 3: return "download " + mux(f) + " ok";
    case 1: return "download segment t" + std::to_string((b0 >> 4) & 1) + " ok";
    case 2: {  // initiate upload response
      std::string s = "upload " + mux(f);
      if (b0 & 0x02) s += " " + bytes((b0 & 0x01) ? 4u - ((b0 >> 2) & 0x03) : 4u);
      else if (b0 & 0x01) s += " size " + std::to_string(u32(f, 4));
      return s;
    }
    case 0: {
      const unsigned n = 7u - ((b0 >> 1) & 0x07);
      return "upload segment t" + std::to_string((b0 >> 4) & 1) + " " + bytes(n) + ((b0 & 0x01) ? " last" : "");
    }
    case 4: return abort_text(f);
    case 5:  // block download: ss in bits 0-1
      switch (b0 & 0x03) {
        case 0: return "block download " + mux(f) + " blksize " + std::to_string(f.data[4]);
        case 2: return "block download ack seq " + std::to_string(f.data[1]) + " blksize " + std::to_string(f.data[2]);
        default: return "block download end ok";
      }
    case 6:  // block upload: ss in bit 0
      if ((b0 & 0x01) == 0)
        return "block upload " + mux(f) + ((b0 & 0x02) ? " size " + std::to_string(u32(f, 4)) : "");
      return "block upload end " + bytes(7u - ((b0 >> 2) & 0x07)) + " crc " + hex_number(u16(f, 1), 4) + "h";
    default: return "scs " + std::to_string(b0 >> 5);
  }
}

std::string sdo(const Frame& f, std::uint8_t node, bool request, const DecodeContext& ctx) {
  // The gateway is every other node's client and its own node's server.
  const bool gateway_sends = (node == ctx.own_node_id) ? !request : request;
  std::string s = std::string("SDO ") + (gateway_sends ? "tx " : "rx ") + std::to_string(node) + " ";
  if (f.len != 8) return s + "malformed (" + bytes(f.len) + ")";
  return s + (request ? sdo_request(f, ctx.block.download[node]) : sdo_response(f, ctx.block.upload[node]));
}

// LSS (CiA 305), master 7E5h -> slaves, slaves 7E4h -> master.
std::string lss(const Frame& f, bool from_master) {
  namespace cs = canopen::lss::cs;
  std::string s = from_master ? "LSS " : "LSS response ";
  if (f.len != 8) return s + "malformed (" + bytes(f.len) + ")";
  const std::uint8_t c = f.data[0];
  static constexpr const char* kParts[] = {"vendor", "product", "revision", "serial"};
  auto result = [&](const char* what) {
    return s + what + (f.data[1] == 0 ? " ok" : " error " + std::to_string(f.data[1]));
  };
  switch (c) {
    case cs::SwitchStateGlobal:
      return s + "switch state global " + (f.data[1] == 1 ? "configuration" : "waiting");
    case cs::ConfigureNodeId:
      return from_master ? s + "configure node-ID " + std::to_string(f.data[1]) : result("configure node-ID");
    case cs::ConfigureBitTiming:
      return from_master ? s + "configure bit timing table " + std::to_string(f.data[1]) + " index " +
                               std::to_string(f.data[2])
                         : result("configure bit timing");
    case cs::ActivateBitTiming: return s + "activate bit timing delay " + std::to_string(u16(f, 1)) + " ms";
    case cs::StoreConfiguration: return from_master ? s + "store configuration" : result("store configuration");
    case cs::SwitchSelectiveResponse: return s + "switch state selective";
    case cs::IdentifySlave: return s + "identify slave";
    case cs::IdentifyNonConfigured: return s + "identify non-configured";
    case cs::IdentifyNonConfiguredSlave: return s + "identify non-configured slave";
    case cs::Fastscan:
      return s + "fastscan" + (f.data[5] == canopen::lss::kFastscanReset ? " reset" : "") + " id " +
             hex_number(u32(f, 1), 8) + "h bit " + std::to_string(f.data[5]) + " sub " + std::to_string(f.data[6]) +
             " next " + std::to_string(f.data[7]);
    case cs::InquireNodeId:
      return from_master ? s + "inquire node-ID" : s + "node-ID " + std::to_string(f.data[1]);
    default: break;
  }
  if (c >= cs::SwitchSelectiveVendor && c < cs::SwitchSelectiveVendor + 4)
    return s + "switch state selective " + kParts[c - cs::SwitchSelectiveVendor] + " " + hex_number(u32(f, 1), 8) + "h";
  if (c >= cs::IdentifyVendor && c <= cs::IdentifySerialHigh) {
    static constexpr const char* kRanges[] = {"vendor",   "product",    "revision low",
                                              "revision high", "serial low", "serial high"};
    return s + "identify " + kRanges[c - cs::IdentifyVendor] + " " + hex_number(u32(f, 1), 8) + "h";
  }
  if (c >= cs::InquireVendor && c < cs::InquireVendor + 4)
    return from_master ? s + "inquire " + kParts[c - cs::InquireVendor]
                       : s + kParts[c - cs::InquireVendor] + " " + hex_number(u32(f, 1), 8) + "h";
  return s + "cs " + hex_number(c, 2) + "h";
}

}  // namespace

std::string decode(const Frame& f, const DecodeContext& ctx) {
  if (f.extended()) return "raw";
  const std::uint32_t id = f.id;
  const std::uint32_t fn = id & 0x780;  // function code (7.3.5, table 72)
  const auto node = static_cast<std::uint8_t>(id & 0x7F);
  if (id == 0x000) return f.remote() ? "raw" : nmt(f);
  if (id == 0x080) {
    if (f.remote()) return "raw";
    if (f.len == 0) return "SYNC";
    if (f.len == 1) return "SYNC " + std::to_string(f.data[0]);
    return "SYNC malformed (" + bytes(f.len) + ")";
  }
  if (id == 0x100) return f.remote() ? "raw" : time_of_day(f);
  if (id == canopen::lss::kMasterCobId) return lss(f, true);
  if (id == canopen::lss::kSlaveCobId) return lss(f, false);
  if (node == 0) return "raw";
  switch (fn) {
    case 0x080: return emcy(f, node);
    case 0x180: case 0x280: case 0x380: case 0x480:
      return "TPDO" + std::to_string((fn - 0x080) >> 8) + " " + std::to_string(node) + (f.remote() ? " RTR" : "");
    case 0x200: case 0x300: case 0x400: case 0x500:
      return "RPDO" + std::to_string((fn - 0x100) >> 8) + " " + std::to_string(node) + (f.remote() ? " RTR" : "");
    case 0x580: return f.remote() ? "raw" : sdo(f, node, false, ctx);
    case 0x600: return f.remote() ? "raw" : sdo(f, node, true, ctx);
    case 0x700: return error_control(f, node);
    default: return "raw";
  }
}

Service classify(const Frame& f) {
  // Mirrors decode(): every frame decode() calls "raw" is "other" here.
  if (f.extended()) return {"other"};
  const std::uint32_t id = f.id;
  const auto node = static_cast<std::uint8_t>(id & 0x7F);
  if (id == 0x000) {
    if (f.remote()) return {"other"};
    return {"nmt", static_cast<std::uint8_t>(f.len == 2 && f.data[1] <= 0x7F ? f.data[1] : 0)};
  }
  if (id == 0x080) return {f.remote() ? "other" : "sync"};
  if (id == 0x100) return {f.remote() ? "other" : "time"};
  if (id == canopen::lss::kMasterCobId || id == canopen::lss::kSlaveCobId) return {"lss"};
  if (node == 0) return {"other"};
  switch (id & 0x780) {
    case 0x080: return {"emcy", node};
    case 0x180: case 0x280: case 0x380: case 0x480: return {"tpdo", node};
    case 0x200: case 0x300: case 0x400: case 0x500: return {"rpdo", node};
    case 0x580: case 0x600: return f.remote() ? Service{"other"} : Service{"sdo", node};
    case 0x700: return {"error-control", node};
    default: return {"other"};
  }
}

void track_sdo_block(const Frame& f, SdoBlockState& st) {
  if (f.extended() || f.remote() || f.len != 8) return;
  const std::uint32_t fn = f.id & 0x780;
  const std::size_t node = f.id & 0x7F;
  if (node == 0 || (fn != 0x580 && fn != 0x600)) return;
  const std::uint8_t b0 = f.data[0];
  const bool request = fn == 0x600;
  if (request && st.download[node]) {
    if (b0 & 0x80) st.download[node] = false;  // the last segment; the end request follows
    return;
  }
  if (!request && st.upload[node]) {
    if (b0 & 0x80) st.upload[node] = false;
    return;
  }
  // Acks (either way) keep the phase: segments go on until the one with
  // c set, the last of the transfer; then the end exchange is commands.
  const unsigned cmd = b0 >> 5;
  if (cmd == 4) {  // abort, either way
    st.download[node] = st.upload[node] = false;
  } else if (!request && cmd == 5 && (b0 & 0x03) == 0) {
    st.download[node] = true;  // initiate block download response: sub-blocks follow
  } else if (request && cmd == 5 && (b0 & 0x03) == 3) {
    st.upload[node] = true;  // start upload: the server sends a sub-block
  }
}

}  // namespace gateway::trace
