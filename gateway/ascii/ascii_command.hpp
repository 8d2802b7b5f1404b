// The CiA 309-3 ASCII command language as CANopenNode's gateway speaks it
// (facts B.1), so its `cocomm` client and existing scripts work unchanged:
// the line framing, one command line parsed into a typed Line, the values
// of every datatype parsed and printed as CANopenNode does, and the
// response texts ("[seq] OK", "[seq] ERROR:101 #Syntax error.",
// "[seq] ERROR:0x06020000 #...").
//
// Sans-I/O: no sockets, clocks or threads; the server (ascii_server.hpp)
// feeds bytes and writes the texts. Pure functions and value types, except
// LineFramer and ValuePrinter (plain state, one owner); thread safety as
// for any value.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "canopen/events.hpp"
#include "canopen/lss/frames.hpp"
#include "canopen/types.hpp"

namespace gateway::ascii {

// The internal error codes of CiA 309-3 (CANopenNode's CO_GTWA_respErrorCode_t).
enum class Error : std::uint16_t {
  RequestNotSupported = 100,
  Syntax = 101,
  InternalState = 102,
  Timeout = 103,
  NoDefaultNet = 104,
  NoDefaultNode = 105,
  UnsupportedNet = 106,
  UnsupportedNode = 107,
  LostGuarding = 200,
  LostConnection = 201,
  HeartbeatStarted = 202,
  HeartbeatLost = 203,
  WrongNmtState = 204,
  BootUp = 205,
  ErrorPassive = 300,
  BusOff = 301,
  CanBufferOverflow = 303,
  CanInit = 304,
  CanActive = 305,
  PdoAlreadyUsed = 400,
  PdoLengthExceeded = 401,
  LssManufacturer = 501,
  LssNodeIdNotSupported = 502,
  LssBitrateNotSupported = 503,
  LssStoreFailed = 504,
  LssMedia = 505,
  OutOfMemory = 600,
};

// "Syntax error." (the meaning the standard gives the code); "-" for a code
// not in the table.
std::string_view error_text(Error e);

// ---- datatypes -------------------------------------------------------------

// CANopenNode's datatype table (facts B.1), in its order: `hex` first (the
// default of a read without a datatype). No t/td (not in that table).
enum class Datatype : std::uint8_t {
  hex, b, i8, i16, i32, i64, u8, u16, u32, u64, x8, x16, x32, x64, r32, r64, vs, os, us, d
};
inline constexpr std::size_t kDatatypeCount = 20;

std::string_view datatype_name(Datatype t);                         // "u32"
std::optional<Datatype> datatype_from_name(std::string_view name);  // case-insensitive
// The size of a fixed-size datatype; nullopt for hex, vs, os, us, d.
std::optional<std::size_t> datatype_size(Datatype t);

// The value text of a write as CANopenNode reads it: numbers as C's strtoul/
// strtol with base 0 (0x hex, leading 0 octal), range-checked for the type;
// r32/r64 as strtof/strtod; vs one word or "double-quoted" with "" for a
// quote; os/us/d base64 (RFC 2045, one line); hex as two-digit groups,
// optionally space separated. `text` is the rest of the line after the
// datatype; a '#' comment may follow the value. nullopt on a syntax error or
// an empty value (both error 101).
std::optional<canopen::Bytes> parse_value(Datatype t, std::string_view text);

// Prints a value read as CANopenNode does, in chunks, so a large upload is
// written out piece by piece: a fixed-size type whose size matches the data
// as a number ("%u", "%d", "0x%08X", "%g"), anything else of a fixed-size
// type and `hex` as "XX XX ..."; vs in double quotes ("" for a quote, NUL
// and CR left out); os/us/d as base64 without line breaks.
class ValuePrinter {
 public:
  // `total`: the whole value's size (decides number or hex).
  ValuePrinter(Datatype t, std::size_t total);
  // Appends the text of the next `chunk` bytes to `out`; `last`: no more
  // data follows (closing quote, base64 padding).
  void print(std::span<const std::uint8_t> chunk, bool last, std::string& out);

 private:
  Datatype type_;
  std::size_t total_;
  bool started_ = false;
  std::uint32_t b64_bits_ = 0;  // pending base64 input bits
  int b64_count_ = 0;           // how many bytes are pending (0..2)
};

// The whole value as one text (tests, small values).
std::string print_value(Datatype t, std::span<const std::uint8_t> data);

// ---- commands --------------------------------------------------------------

// The identity of an LSS slave (1018h sub 1..4).
// The LSS address (1018h sub 1..4) as the stack and the request core have it.
using LssIdentity = canopen::lss::Identity;

// lss_allnodes' scan type per identity word: 0 fastscan, 1 ignore, 2 match.
enum class LssScan : std::uint8_t { scan = 0, ignore = 1, match = 2 };

// LSS commands (CiA 309-3, facts B.1), parsed; the server hands them to its
// LSS handler (ascii_server.hpp), which executes them.
struct LssSwitchGlobal {
  bool configuration = false;  // lss_switch_glob 1: every slave to configuration state
  friend bool operator==(const LssSwitchGlobal&, const LssSwitchGlobal&) = default;
};
struct LssSwitchSelective {
  LssIdentity identity;
  friend bool operator==(const LssSwitchSelective&, const LssSwitchSelective&) = default;
};
struct LssSetNode {
  std::uint8_t node = 0;  // 0..127 or 0xFF (unconfigured), as the parser accepts
  friend bool operator==(const LssSetNode&, const LssSetNode&) = default;
};
struct LssConfigureBitrate {
  std::uint8_t table_selector = 0;  // only 0 (the CiA 301 table) is accepted
  std::uint8_t table_index = 0;     // 0..9 without 5 (lss_bitrate_kbit)
  friend bool operator==(const LssConfigureBitrate&, const LssConfigureBitrate&) = default;
};
struct LssActivateBitrate {
  std::uint16_t switch_delay_ms = 0;
  friend bool operator==(const LssActivateBitrate&, const LssActivateBitrate&) = default;
};
struct LssStore {
  friend bool operator==(const LssStore&, const LssStore&) = default;
};
struct LssInquireAddress {
  std::optional<std::uint8_t> lss_sub;  // 0 vendor, 1 product, 2 revision, 3 serial; nullopt: all four
  friend bool operator==(const LssInquireAddress&, const LssInquireAddress&) = default;
};
struct LssGetNode {
  friend bool operator==(const LssGetNode&, const LssGetNode&) = default;
};
struct LssFastscan {
  std::uint16_t timeout_ms = 100;  // per step; 0 in the command means the default 100
  friend bool operator==(const LssFastscan&, const LssFastscan&) = default;
};
struct LssAllNodes {
  std::uint16_t timeout_ms = 100;
  std::uint8_t first_node = 2;  // 1..127
  bool store = true;
  std::array<LssScan, 4> scan{};  // vendor, product, revision, serial
  LssIdentity match;              // the words scanned as `match`
  friend bool operator==(const LssAllNodes&, const LssAllNodes&) = default;
};
using LssCommand = std::variant<LssSwitchGlobal, LssSwitchSelective, LssSetNode, LssConfigureBitrate,
                                LssActivateBitrate, LssStore, LssInquireAddress, LssGetNode, LssFastscan, LssAllNodes>;

// lss_conf_bitrate's table index in kbit/s (0 = 1000 ... 8 = 10); 0 for 9
// (automatic) and the reserved 5.
unsigned lss_bitrate_kbit(std::uint8_t table_index);

struct SdoReadCmd {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  Datatype type = Datatype::hex;
  friend bool operator==(const SdoReadCmd&, const SdoReadCmd&) = default;
};
struct SdoWriteCmd {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  Datatype type = Datatype::hex;
  canopen::Bytes data;  // the value as it goes on the bus
  friend bool operator==(const SdoWriteCmd&, const SdoWriteCmd&) = default;
};
struct NmtCmd {
  canopen::NmtCommand command = canopen::NmtCommand::Start;
  friend bool operator==(const NmtCmd&, const NmtCmd&) = default;
};
struct SetNetwork {
  std::uint16_t net = 0;
  friend bool operator==(const SetNetwork&, const SetNetwork&) = default;
};
struct SetNode {
  std::uint8_t node = 0;  // 1..127
  friend bool operator==(const SetNode&, const SetNode&) = default;
};
struct SetSdoTimeout {
  std::uint16_t ms = 0;  // 1..65535
  friend bool operator==(const SetSdoTimeout&, const SetSdoTimeout&) = default;
};
struct SetSdoBlock {
  bool on = false;
  friend bool operator==(const SetSdoBlock&, const SetSdoBlock&) = default;
};
enum class HelpTopic : std::uint8_t { general, datatype, lss };
struct Help {
  HelpTopic topic = HelpTopic::general;
  friend bool operator==(const Help&, const Help&) = default;
};

using Command = std::variant<SdoReadCmd, SdoWriteCmd, NmtCmd, SetNetwork, SetNode, SetSdoTimeout, SetSdoBlock, Help,
                            LssCommand>;

// A client's defaults (`set ...`); the server keeps one per connection.
struct Defaults {
  std::uint16_t net = 1;               // the gateway's first network until `set network`
  std::optional<std::uint8_t> node;    // none until `set node` (error 105)
  std::uint16_t sdo_timeout_ms = 500;  // CiA 309-3 / CANopenNode default
  bool sdo_block = false;
};

// One parsed command line: net and node resolved (given, or the defaults).
struct Line {
  std::uint32_t seq = 0;
  std::uint16_t net = 0;
  std::uint8_t node = 0;  // SDO 1..127, NMT 0..127 (0: all); 0 where unused
  Command command;
  friend bool operator==(const Line&, const Line&) = default;
};

struct Parsed {
  enum class Kind : std::uint8_t { empty, command, error };
  Kind kind = Kind::empty;  // empty: a blank or comment-only line, answered "\r\n"
  Line line;                // kind == command
  Error error = Error::Syntax;
  // The sequence number when the line had a valid one (also for errors);
  // nullopt: CANopenNode answers with the previous one.
  std::optional<std::uint32_t> seq;
};

// Parses one line (without its '\n'; a trailing '\r' is white space).
// Error precedence as CANopenNode: a missing default node (105) before
// the arguments' syntax (101); an unknown command 100.
Parsed parse_line(std::string_view line, const Defaults& defaults);

// The canonical text of a parsed line ("[7] 1 5 w 0x1017 0 u16 1000"):
// parsing it again with any defaults gives the same Line.
std::string format_line(const Line& line);

// ---- line framing -----------------------------------------------------------

// Splits a byte stream into lines at '\n' (CR LF or bare LF), at most
// `max_line` bytes each. A longer line is reported once as too long and
// the rest of it, up to its '\n', discarded.
class LineFramer {
 public:
  explicit LineFramer(std::size_t max_line) : max_(max_line) {}
  struct Item {
    std::string text;        // the line without '\n'
    bool too_long = false;   // text: its first max_line bytes
  };
  // Appends `data` and moves every complete line (and the report of each
  // over-long one) to `out`.
  void feed(std::string_view data, std::vector<Item>& out);
  std::size_t buffered() const { return buf_.size(); }

 private:
  std::size_t max_;
  std::string buf_;
  bool discarding_ = false;
};

// ---- responses --------------------------------------------------------------

std::string ok_response(std::uint32_t seq);                   // "[seq] OK\r\n"
std::string error_response(std::uint32_t seq, Error e);       // "[seq] ERROR:101 #Syntax error.\r\n"
// A refusal by role (the core's 401 or 403, else nullopt): "[seq] ERROR:100
// #Request not supported. role operator may not do this (needs admin);
// ascii.role ... sets the role ...\r\n".
std::optional<std::string> role_refusal(std::uint32_t seq, int status, std::string_view detail);
std::string abort_response(std::uint32_t seq, std::uint32_t abort_code);  // "[seq] ERROR:0x06020000 #...\r\n"
std::string empty_response();                                // "\r\n"
std::string_view help_text(HelpTopic topic);                 // starts "\n", ends "\r\n"
// LSS answers (facts B.1): lss_get_node "[seq] 0x05"; one identity word
// "[seq] 0x000005A1"; lss_inquire_addr without argument and _lss_fastscan
// "[seq] 0x... 0x... 0x... 0x..."; lss_allnodes' lines per assignment and
// its end ("# Found N nodes, search finished.\n[seq] OK\r\n").
std::string lss_node_response(std::uint32_t seq, std::uint8_t node);
std::string lss_word_response(std::uint32_t seq, std::uint32_t value);
std::string lss_identity_response(std::uint32_t seq, const LssIdentity& id);
std::string lss_assigned_line(std::uint8_t node, const LssIdentity& id);
std::string lss_allnodes_finished(std::uint32_t seq, unsigned found);

}  // namespace gateway::ascii
