// The answers: OK, errors, SDO aborts, the help texts and the LSS answers.
#include "ascii/ascii_command.hpp"
#include "ascii/ascii_text.hpp"
#include "canopen/sdo/abort.hpp"

namespace gateway::ascii {

using namespace detail;

// ---- responses -----------------------------------------------------------------

std::string ok_response(std::uint32_t seq) { return "[" + std::to_string(seq) + "] OK\r\n"; }

std::string error_response(std::uint32_t seq, Error e) {
  return "[" + std::to_string(seq) + "] ERROR:" + std::to_string(static_cast<unsigned>(e)) + " #" +
         std::string(error_text(e)) + "\r\n";
}

std::optional<std::string> role_refusal(std::uint32_t seq, int status, std::string_view detail) {
  if (status != 401 && status != 403) return std::nullopt;
  std::string line = error_response(seq, Error::RequestNotSupported);
  line.insert(line.size() - 2, " " + std::string(status == 401 ? "the ASCII clients' role is none" : detail) +
                                   "; ascii.role in the gateway's configuration sets the role of ASCII clients");
  return line;
}

std::string abort_response(std::uint32_t seq, std::uint32_t abort_code) {
  return "[" + std::to_string(seq) + "] ERROR:" + printf_string("0x%08lX", static_cast<unsigned long>(abort_code)) +
         " #" + std::string(canopen::sdo_abort_text(abort_code)) + "\r\n";
}

std::string empty_response() { return "\r\n"; }

std::string_view help_text(HelpTopic topic) {
  // Written for this gateway; the layout (a leading "\n", lines ending in
  // "\n", the last one in "\r\n") is what CiA 309-3 clients expect.
  static constexpr std::string_view kGeneral =
      "\n"
      "Every command starts with \"[<sequence>]\" (a number echoed in the answer):\n"
      "[[<net>] <node>] r[ead] <index> <subindex> [<datatype>]   SDO upload (datatype default: hex)\n"
      "[[<net>] <node>] w[rite] <index> <subindex> <datatype> <value>   SDO download\n"
      "[[<net>] <node>] start | stop | preop[erational]   NMT command (node 0: all nodes)\n"
      "[[<net>] <node>] reset node | reset comm[unication]   NMT reset\n"
      "set network <net> | set node <node>   this connection's defaults\n"
      "set sdo_timeout <ms> | set sdo_block <0|1>   SDO options (defaults 500 ms, no block)\n"
      "help [datatype|lss]   this text, the datatypes or the LSS commands\n"
      "\n"
      "Answers: \"[<sequence>] OK\", \"[<sequence>] <value>\", \"[<sequence>] ERROR:<code>\"\n"
      "(100 not supported, 101 syntax, 102 internal state, 103 time-out, 104/105 no\n"
      "default net/node, 106/107 unsupported net/node, 600 line too long) or\n"
      "\"[<sequence>] ERROR:0x<SDO abort code>\". Networks are the gateway's, from 1.\n"
      "Lines end with LF or CR LF; '#' starts a comment; commands are case-insensitive.\r\n";
  static constexpr std::string_view kDatatype =
      "\n"
      "Datatypes:\n"
      "b                   boolean (0 or 1)\n"
      "i8 i16 i32 i64      signed integers\n"
      "u8 u16 u32 u64      unsigned integers\n"
      "x8 x16 x32 x64      unsigned integers shown in hex\n"
      "r32 r64             floating point\n"
      "vs                  visible string (in double quotes when it has spaces, \"\" for \")\n"
      "os us d             octet string, unicode string, domain: base64 on one line\n"
      "hex                 bytes in hex, optionally separated by spaces\r\n";
  static constexpr std::string_view kLss =
      "\n"
      "LSS commands (CiA 305), \"[<sequence>] [<net>]\" first:\n"
      "lss_switch_glob <0|1>                      all slaves waiting (0) or configuration (1)\n"
      "lss_switch_sel <vendor> <product> <revision> <serial>   select one slave\n"
      "lss_set_node <node>                        node-ID of the selected slave\n"
      "lss_conf_bitrate 0 <index>                 bit timing: 0=1000 1=800 2=500 3=250\n"
      "                                           4=125 6=50 7=20 8=10 kbit/s, 9=auto\n"
      "lss_activate_bitrate <delay ms>            switch every slave to the new bit rate\n"
      "lss_store                                  selected slave stores its configuration\n"
      "lss_inquire_addr [<0..3>]                  identity word(s) of the selected slave\n"
      "lss_get_node                               node-ID of the selected slave\n"
      "_lss_fastscan [<timeout ms>]               find one unconfigured slave (default 100 ms)\n"
      "lss_allnodes [<timeout ms> [<first node> <store 0|1>\n"
      "             [<scan> <vendor> <scan> <product> <scan> <revision> <scan> <serial>]]]\n"
      "                                           give every unconfigured slave a node-ID\n"
      "                                           (scan: 0 fastscan, 1 ignore, 2 match)\r\n";
  switch (topic) {
    case HelpTopic::datatype: return kDatatype;
    case HelpTopic::lss: return kLss;
    case HelpTopic::general: break;
  }
  return kGeneral;
}

std::string lss_node_response(std::uint32_t seq, std::uint8_t node) {
  return "[" + std::to_string(seq) + "] " + printf_string("0x%02X", static_cast<unsigned>(node)) + "\r\n";
}

std::string lss_word_response(std::uint32_t seq, std::uint32_t value) {
  return "[" + std::to_string(seq) + "] " + printf_string("0x%08lX", static_cast<unsigned long>(value)) + "\r\n";
}

namespace {
std::string identity_words(const LssIdentity& id) {
  return printf_string("0x%08lX 0x%08lX 0x%08lX 0x%08lX", static_cast<unsigned long>(id.vendor_id),
                       static_cast<unsigned long>(id.product_code), static_cast<unsigned long>(id.revision),
                       static_cast<unsigned long>(id.serial));
}
}  // namespace

std::string lss_identity_response(std::uint32_t seq, const LssIdentity& id) {
  return "[" + std::to_string(seq) + "] " + identity_words(id) + "\r\n";
}

std::string lss_assigned_line(std::uint8_t node, const LssIdentity& id) {
  return "# Node-ID " + std::to_string(node) + " assigned to: " + identity_words(id) + "\n";
}

std::string lss_allnodes_finished(std::uint32_t seq, unsigned found) {
  return "# Found " + std::to_string(found) + " nodes, search finished.\n" + ok_response(seq);
}

}  // namespace gateway::ascii
