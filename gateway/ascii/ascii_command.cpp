// The ASCII language (ascii_command.hpp): the error texts and the line
// framing. Values are in ascii_values.cpp, the command line's parser and
// canonical text in ascii_parse.cpp, the answers in ascii_answer.cpp;
// ascii_text.hpp holds what they share.
#include "ascii/ascii_command.hpp"

namespace gateway::ascii {

std::string_view error_text(Error e) {
  switch (e) {
    case Error::RequestNotSupported: return "Request not supported.";
    case Error::Syntax: return "Syntax error.";
    case Error::InternalState: return "Request not processed due to internal state.";
    case Error::Timeout: return "Time-out.";
    case Error::NoDefaultNet: return "No default net set.";
    case Error::NoDefaultNode: return "No default node set.";
    case Error::UnsupportedNet: return "Unsupported net.";
    case Error::UnsupportedNode: return "Unsupported node.";
    case Error::LostGuarding: return "Lost guarding message.";
    case Error::LostConnection: return "Lost connection.";
    case Error::HeartbeatStarted: return "Heartbeat started.";
    case Error::HeartbeatLost: return "Heartbeat lost.";
    case Error::WrongNmtState: return "Wrong NMT state.";
    case Error::BootUp: return "Boot-up.";
    case Error::ErrorPassive: return "Error passive.";
    case Error::BusOff: return "Bus off.";
    case Error::CanBufferOverflow: return "CAN buffer overflow.";
    case Error::CanInit: return "CAN init.";
    case Error::CanActive: return "CAN active.";
    case Error::PdoAlreadyUsed: return "PDO already used.";
    case Error::PdoLengthExceeded: return "PDO length exceeded.";
    case Error::LssManufacturer: return "LSS manufacturer error.";
    case Error::LssNodeIdNotSupported: return "LSS node-ID not supported.";
    case Error::LssBitrateNotSupported: return "LSS bit-rate not supported.";
    case Error::LssStoreFailed: return "LSS parameter storing failed.";
    case Error::LssMedia: return "LSS media error.";
    case Error::OutOfMemory: return "Running out of memory.";
  }
  return "-";
}

// ---- framing -------------------------------------------------------------------

void LineFramer::feed(std::string_view data, std::vector<Item>& out) {
  while (!data.empty()) {
    const auto nl = data.find('\n');
    const std::string_view piece = data.substr(0, nl);
    if (discarding_) {
      // The rest of an over-long line, up to its end.
    } else if (buf_.size() + piece.size() > max_) {
      buf_.append(piece.substr(0, max_ - buf_.size()));
      out.push_back({std::move(buf_), true});
      buf_.clear();
      discarding_ = true;
    } else {
      buf_.append(piece);
    }
    if (nl == std::string_view::npos) return;
    if (!discarding_) {
      out.push_back({std::move(buf_), false});
      buf_.clear();
    }
    discarding_ = false;
    data.remove_prefix(nl + 1);
  }
}

}  // namespace gateway::ascii
