// The ASCII interface's LSS commands (lss_*, _lss_fastscan, lss_allnodes;
// facts B.1) executed by the request core's LSS commands (contract "LSS
// master"): one core::Request per command with the client's caller, so the
// role (admin, as every LSS front end; with the default ascii.role operator
// they are answered ERROR:100), the one-LSS-operation-per-network rule and
// the audit lines are the core's. Answers as CANopenNode's gateway writes
// them: "[seq] OK", "[seq] 0x05" (lss_get_node), "[seq] 0x000005A1" (one
// identity word), four words (lss_inquire_addr without argument,
// _lss_fastscan), lss_allnodes' "# Node-ID n assigned to: ..." lines and
// "# Found N nodes, search finished." before its OK. Errors: 103 no answer
// (also a fastscan nobody answered), 102 another LSS operation runs or the
// bus is down, 501..505 the slave's CiA 305 error code, 100 not permitted
// for the client's role or an lss_allnodes with ignore/match scan types
// (only fastscan of all four words is done), 101 an argument the core
// refuses, 106 an unknown network.
//
// Thread safety: the handler runs on the io thread, as the server calls it.
#pragma once

#include "ascii/ascii_server.hpp"

namespace gateway::core {
class RequestCore;
}

namespace gateway::ascii {

// `core` MUST outlive the server the handler is given to.
LssHandler make_lss_handler(core::RequestCore& core);

}  // namespace gateway::ascii
