// The typed request core's vocabulary: who asks (Caller), what they ask for
// (one Command), and the one answer (Result: a typed success or a Problem).
// Every front end (REST, MQTT, WebSocket, CiA 309-3 ASCII, Sparkplug B
// commands) decodes its wire format into a Request once, hands it to
// RequestCore::execute (request_core.hpp) and encodes the Result itself.
// Values are typed (canopen::Value) or literals the core types by the EDS
// (WriteValue); no wire format's representation gets past a front end.
// A new operation is a Command alternative, its Result alternative and its
// descriptor (core/operation.hpp: it does not compile without one).
//
// Plain value types; thread safety as for any value.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <variant>
#include <vector>

#include "canopen/events.hpp"
#include "canopen/literal.hpp"
#include "core/node_entry.hpp"
#include "canopen/lss/frames.hpp"
#include "canopen/pdo/config_reader.hpp"
#include "canopen/types.hpp"
#include "role.hpp"

namespace gateway::core {

enum class Transport : std::uint8_t { rest, mqtt, websocket, ascii, sparkplug };

// Who asks. A transport that checked the caller itself (HTTP's authorizer)
// sets `authenticated`, `role`, `who` and `key`; otherwise (MQTT) it passes
// the bearer `token` that came with the request ("" = none) and the core
// identifies the caller from it (auth::TokenStore) and rate-limits it.
struct Caller {
  Transport transport = Transport::rest;
  std::string who;             // identity for the audit log ("" = anonymous)
  bool authenticated = false;  // role, who and key are set by the transport
  Role role = Role::None;
  // Who counts as one caller for per-caller limits (a share of each node's
  // SDO queue, the request rate limit): auth::token_caller,
  // auth::address_caller or auth::kTokenlessMqttCaller.
  std::string key;
  std::string token;  // not authenticated: the bearer token to check
};

// The operations, for roles and for requests that could not be decoded.
enum class Operation : std::uint8_t {
  sdo_read, sdo_write, nmt, rpdo_write, sync, pdo_config_read, lss,
  // Remote configuration and maintenance (contract section of that name).
  config_read, config_write, dcf_read, dcf_write, store, program
};

// SDO upload of index/sub from `node` (the gateway's own node-ID: its own
// dictionary answers). type: as asked, else the node's EDS/DCF entry's, else
// DOMAIN (raw bytes).
struct SdoRead {
  std::uint8_t node = 0;
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::optional<canopen::DataType> type;
  // How the transfer runs (CiA 309-3 `set sdo_timeout` / `set sdo_block`):
  // nullopt = the SDO client's default for the node.
  std::optional<std::chrono::milliseconds> timeout = std::nullopt;
  // true: block transfer; false: expedited/segmented only; nullopt: the
  // client decides (block for large transfers where the node allows it).
  std::optional<bool> block = std::nullopt;
};

// A value to write: typed by the front end (the ASCII interface's datatype,
// a Sparkplug metric typed from the EDS), or a Literal as the caller wrote
// it (REST, MQTT) that the core types by the request's `type` or the EDS/DCF
// entry's. Never a wire format's own representation.
using WriteValue = std::variant<canopen::Value, canopen::Literal>;

// SDO download, checked against the type and the EDS/DCF limits before
// anything goes on the bus. A typed value's type is the request's `type`.
struct SdoWrite {
  std::uint8_t node = 0;
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::optional<canopen::DataType> type;
  WriteValue value;
  // How the transfer runs (CiA 309-3 `set sdo_timeout` / `set sdo_block`):
  // nullopt = the SDO client's default for the node.
  std::optional<std::chrono::milliseconds> timeout = std::nullopt;
  // true: block transfer; false: expedited/segmented only; nullopt: the
  // client decides (block for large transfers where the node allows it).
  std::optional<bool> block = std::nullopt;
};

// NMT command to `node` (0 = all nodes).
struct Nmt {
  std::uint8_t node = 0;
  canopen::NmtCommand command = canopen::NmtCommand::Start;
};

// One value of an RPDO write, by the object it is mapped from. `invalid`:
// what was wrong with this item as sent (answered 400, in item order, once
// the items before it passed: the core checks them one by one).
struct RpdoItem {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  WriteValue value;
  std::string invalid;
};

// Process data to `node`'s RPDO `number`: values by object, or the raw data;
// typed and checked by the core against the RPDO's mapping in effect and
// the EDS limits (core/rpdo_values.hpp). `invalid`: what was wrong with the
// body as a whole (answered 400 once the RPDO is known to be in use).
struct RpdoWrite {
  std::uint8_t node = 0;
  std::uint16_t number = 0;
  std::vector<RpdoItem> values;  // empty when `raw` is set
  std::optional<canopen::Bytes> raw;
  std::string invalid;
};

// One SYNC on the network, with the counter when given (1..240).
struct Sync {
  std::optional<std::uint8_t> counter;
};

// Read `node`'s PDO configuration from the device by SDO.
struct PdoConfigRead {
  std::uint8_t node = 0;
};

// A request whose wire form the transport could not decode, though the
// path or topic said which operation it was for. It is answered 400 with
// `detail`, but only after the caller was identified, rate-limited, the
// address checked and (for SDO) the role checked, as a well-formed request
// would be: bad input gets no cheaper way past those. `in_address`: the
// fault is in the path (node, index, ...), answered before the bus state is.
struct Undecodable {
  Operation operation = Operation::sdo_read;
  std::uint8_t node = 0;
  std::string detail;
  bool in_address = false;
};

// ---- LSS (CiA 305; contract "LSS master") -------------------------------------
// Every LSS command needs role admin (REST, ASCII and any other front end).
// One LSS operation runs per network at a time; another is refused with 409
// while it runs (a multi-step one such as LssConfigure holds the network's
// LSS master from its first frame to its last).

// A device's LSS address: its identity object 1018h sub 1..4.
using LssAddress = canopen::lss::Identity;

// Fastscan (facts C.2): all slaves back to waiting, then finds one
// unconfigured device (node-ID FFh) and leaves it in configuration state.
// `timeout` per step; nullopt = the master's default.
struct LssFastscan {
  std::optional<std::chrono::milliseconds> timeout;
};

// All back to waiting, select `address`, configure its node-ID (and bit
// timing: `bitrate` in bit/s, one of the CiA 301 table's), store when asked,
// all back to waiting (an unconfigured device then boots with the new ID).
struct LssConfigure {
  LssAddress address;
  std::uint8_t node_id = 0;
  std::optional<std::uint32_t> bitrate;
  bool store = true;
};

// Fastscan until no unconfigured device answers, giving each found device
// the next free node-ID from `first_node_id` on (free: not the gateway's,
// not configured, not heard on the network), storing when asked.
struct LssAssignAll {
  std::uint8_t first_node_id = 1;
  bool store = true;
  std::optional<std::chrono::milliseconds> timeout;  // per fastscan step
};

// What the last scan (fastscan or assign-all) on the network found.
struct LssDevices {};

// The single services (the ASCII interface's lss_* commands), as CiA 305
// defines them; none switches states by itself.
struct LssSwitchGlobal {
  bool configuration = false;  // false: all to waiting
};
struct LssSwitchSelective {
  LssAddress address;
};
struct LssSetNodeId {
  std::uint8_t node_id = 0;  // 1..127, or 0xFF (unconfigured)
};
struct LssSetBitTiming {
  std::uint8_t table = 0;  // 0: the CiA 301 table
  std::uint8_t index = 0;  // 0=1000 1=800 2=500 3=250 4=125 6=50 7=20 8=10 kbit/s, 9 auto
};
struct LssActivateBitTiming {
  std::uint16_t delay_ms = 0;
};
struct LssStore {};
// The first four in fastscan's part order (canopen::lss::Part).
enum class LssInquiry : std::uint8_t { vendor_id, product_code, revision, serial, node_id };
// Inquire of the one device in configuration state: one value, or (nullopt)
// its whole LSS address.
struct LssInquire {
  std::optional<LssInquiry> what;
};

// ---- Remote configuration and maintenance -----------------------------------
// Contract "Remote configuration and maintenance". Roles: reading the
// configuration and a DCF read-back viewer; store/restore operator; the
// rest admin (required_role).

// The node's settings (one `nodes:` entry of the YAML) and where they come from.
struct NodeConfigRead {
  std::uint8_t node = 0;
};
// New settings for the node (one `nodes:` entry, typed: core/node_entry.hpp),
// applied at once and kept in state-dir. The front end decodes them by the
// configuration file's rules (config/: parse_node_config); what it could
// not decode travels in `invalid` (the parser's reason) and is answered 400
// after the caller, the network and the node-ID were checked, as a decoded
// request's would be. `settings.id` MUST be the node (else 400). Nothing
// changes on error.
struct NodeConfigWrite {
  std::uint8_t node = 0;
  NodeConfig settings;
  // DELETE .../config: drop the state-dir settings (and a kept EDS), back to
  // the YAML's; `settings` is then unused.
  bool revert = false;
  std::string invalid;  // non-empty: the settings did not decode; why
};
// An EDS or DCF file for the node: checked like `canopen-eds check` (400
// with "FILE:LINE: reason"), then used at once and kept in state-dir.
struct NodeEdsWrite {
  std::uint8_t node = 0;
  std::string text;
  std::string file_name;  // for messages and the kept copy ("" = "node<N>.eds")
};
// Reads the node's configurable objects by SDO; answers a DCF of their values.
struct DcfRead {
  std::uint8_t node = 0;
};
// Writes a DCF's values to the node in the boot-up configurator's order,
// one result per object; then optionally store (1010h sub 1) and reset node.
struct DcfApply {
  std::uint8_t node = 0;
  std::string text;
  bool store = false;
  bool reset = false;
};
// 1010h sub 1 "save" (store) / 1011h sub 1 "load" then NMT reset node (restore).
struct NodeStore {
  std::uint8_t node = 0;
  bool restore = false;
};
// CiA 302-3 program download of `image` to 1F50h sub `program`.
struct ProgramDownload {
  std::uint8_t node = 0;
  std::uint8_t program = 1;
  canopen::Bytes image;
};

using Command = std::variant<SdoRead, SdoWrite, Nmt, RpdoWrite, Sync, PdoConfigRead, LssFastscan, LssConfigure,
                             LssAssignAll, LssDevices, LssSwitchGlobal, LssSwitchSelective, LssSetNodeId,
                             LssSetBitTiming, LssActivateBitTiming, LssStore, LssInquire, Undecodable,
                             NodeConfigRead, NodeConfigWrite, NodeEdsWrite, DcfRead, DcfApply, NodeStore,
                             ProgramDownload>;

struct Request {
  Caller caller;
  std::uint32_t network = 0;  // 1-based
  Command command;
  // Refuse with 503 while the network's bus is bus-off or down (REST does;
  // MQTT requests wait in the SDO queue instead).
  bool check_bus = false;
};

// ---- results -----------------------------------------------------------------

// SDO read: the value read; SDO write: the value written.
struct SdoValue {
  canopen::Value value;
};

struct NmtSent {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  canopen::NmtCommand command = canopen::NmtCommand::Start;
};

struct RpdoSent {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  std::uint16_t number = 0;
  std::uint32_t cob_id = 0;
  std::uint8_t transmission_type = 0;
  canopen::Bytes raw;  // the PDO's payload after the write
};

struct SyncSent {
  std::uint32_t network = 0;
  std::optional<std::uint8_t> counter;
};

struct PdoConfigReport {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  canopen::pdo::PdoReadReport report;
};

// LSS results.
// A single LSS service that answers nothing but success (switch, set node-ID,
// bit timing, store).
struct LssDone {
  std::uint32_t network = 0;
};
struct LssFound {
  std::uint32_t network = 0;
  LssAddress address;
};
struct LssAssignment {
  LssAddress address;
  std::uint8_t node_id = 0;
  std::optional<std::uint32_t> bitrate;
  bool stored = false;
};
// LssConfigure: one assignment; LssAssignAll: every one, in order.
struct LssAssigned {
  std::uint32_t network = 0;
  std::vector<LssAssignment> assignments;
};
// A device a scan found, with the node-ID given to it since (if any).
struct LssDeviceSeen {
  LssAddress address;
  std::optional<std::uint8_t> node_id;
};
struct LssDeviceList {
  std::uint32_t network = 0;
  std::vector<LssDeviceSeen> devices;
};
struct LssInquired {
  std::uint32_t network = 0;
  std::optional<LssInquiry> what;  // nullopt: `address` is the answer
  std::uint32_t value = 0;         // node-ID or one address word
  LssAddress address;
};

// Remote configuration results.
// The node's settings and where they come from: "state-dir" (changed at
// run time), "config" (the YAML file or flags), "none" (not configured).
struct NodeConfigView {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  std::optional<NodeConfig> settings;  // nullopt when the node is not configured
  std::string source;
  std::string file;  // source "state-dir": the file that holds the settings
  // NodeEdsWrite: the EDS reader's warnings as it wrote them ("file:line:
  // text", DeviceDescription::warnings) for the uploaded file `eds_name`;
  // the file was accepted.
  std::vector<std::string> warnings;
  std::string eds_name;
};
// One object of a DCF read-back or apply that did not go through.
struct ObjectOutcome {
  std::uint16_t index = 0;
  std::uint8_t sub = 0;
  std::error_code error;  // empty: written / read
  std::string detail;
};
// DcfRead: the DCF text; the objects that aborted are listed in `failed`.
struct DcfDocument {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  std::string text;
  std::size_t objects = 0;  // read successfully
  std::vector<ObjectOutcome> failed;
};
// DcfApply: one outcome per object written, in the order written.
struct DcfApplied {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  std::vector<ObjectOutcome> objects;
  bool stored = false;
  bool reset = false;
  std::optional<ObjectOutcome> store_error;  // store asked, and 1010h sub 1 refused it
};
// NodeStore.
struct NodeStored {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  bool restore = false;
};
// ProgramDownload: done and started; identification = 1F56h sub n when the device has it.
struct ProgramDownloaded {
  std::uint32_t network = 0;
  std::uint8_t node = 0;
  std::uint8_t program = 1;
  std::size_t bytes = 0;
  std::optional<std::uint32_t> identification;
};

// What a device said when it refused an LSS service (CiA 305 error codes).
enum class LssError : std::uint8_t {
  manufacturer,           // error code FFh: manufacturer-specific (see the detail)
  node_id_not_supported,  // configure node-ID, error 1: out of range
  bitrate_not_supported,  // configure bit timing, error 1
  store_not_supported,    // store configuration, error 1
  store_media_error,      // store configuration, error 2: storage media access error
  other,                  // a code CiA 305 reserves
};

// A refusal or failure (RFC 9457 problem details, HTTP status semantics).
struct Problem {
  int status = 500;
  std::string detail;
  std::string title;  // "" = the status' reason phrase
  std::string type;   // "" = about:blank
  std::optional<std::uint32_t> abort_code;  // SDO abort code (422/502/504 of a transfer)
  int retry_after = 0;  // seconds, with 429/503 (HTTP Retry-After); 0 = not said
  // Whether the core had read the command when it refused: only then does
  // a reply echo the correlation id that came inside the command's body.
  bool command_read = true;
  // An LSS slave's refusal (422): what it meant, for front ends with their
  // own codes (the ASCII interface's 501..505).
  std::optional<LssError> lss_error;
};

using Result = std::variant<SdoValue, NmtSent, RpdoSent, SyncSent, PdoConfigReport, LssDone, LssFound, LssAssigned,
                            LssDeviceList, LssInquired, NodeConfigView, DcfDocument, DcfApplied, NodeStored,
                            ProgramDownloaded, Problem>;

// A failed SDO transfer or dictionary access as a Problem: remote (the
// device, or the own dictionary, refused) 422 "SDO abort"; a local timeout
// (05040000h) 504; other local failures 502. All carry the abort code, and
// the CiA 301 text as detail (": " and `context` appended when given).
Problem sdo_problem(std::error_code ec, bool remote, std::string_view context = {});

// The role a command needs: SDO read viewer; SDO write, RPDO write, SYNC,
// PDO configuration read and NMT start/stop/pre-operational operator; NMT
// reset node / reset communication and every LSS command admin; node
// configuration and DCF read viewer, store/restore operator, configuration
// and EDS writes, DCF apply and program download admin.
Role required_role(const Command& command);
Role required_role(Operation op, std::optional<canopen::NmtCommand> nmt = std::nullopt);

std::string_view to_string(Transport t);

// "start" "stop" "preop" "reset-node" "reset-comm" (the API's names).
std::string_view nmt_command_name(canopen::NmtCommand c);
std::optional<canopen::NmtCommand> nmt_command_from_name(std::string_view s);

}  // namespace gateway::core
