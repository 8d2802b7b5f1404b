// One command line: parse_line() into a typed Line, and format_line(), its
// canonical text.
#include <cstring>
#include <type_traits>
#include <variant>

#include "ascii/ascii_command.hpp"
#include "ascii/ascii_text.hpp"

namespace gateway::ascii {

using namespace detail;

unsigned lss_bitrate_kbit(std::uint8_t table_index) {
  constexpr unsigned kTable[] = {1000, 800, 500, 250, 125, 0, 50, 20, 10, 0};
  return table_index < std::size(kTable) ? kTable[table_index] : 0;
}

// ---- parsing -----------------------------------------------------------------

namespace {

struct Fail {
  Error error;
};

// The value token that must be the last one on the line.
template <typename T>
std::optional<T> last_u(Cursor& c, std::uint64_t lo, std::uint64_t hi) {
  const auto tok = c.token();
  if (tok.empty() || !c.at_end()) return std::nullopt;
  auto v = parse_u(tok, lo, hi);
  if (!v) return std::nullopt;
  return static_cast<T>(*v);
}

// A value token that must not be the last one.
template <typename T>
std::optional<T> inner_u(Cursor& c, std::uint64_t lo, std::uint64_t hi) {
  const auto tok = c.token();
  if (tok.empty() || c.at_end()) return std::nullopt;
  auto v = parse_u(tok, lo, hi);
  if (!v) return std::nullopt;
  return static_cast<T>(*v);
}

std::variant<Command, Fail> parse_lss(const std::string& cmd, Cursor& c) {
  const Fail syntax{Error::Syntax};
  if (cmd == "lss_switch_glob") {
    if (c.at_end()) return syntax;
    auto v = last_u<std::uint8_t>(c, 0, 1);
    if (!v) return syntax;
    return Command{LssCommand{LssSwitchGlobal{*v == 1}}};
  }
  if (cmd == "lss_switch_sel") {
    if (c.at_end()) return syntax;
    auto v = inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF);
    auto p = v ? inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : std::nullopt;
    auto r = p ? inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : std::nullopt;
    auto s = r ? last_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : std::nullopt;
    if (!s) return syntax;
    return Command{LssCommand{LssSwitchSelective{{*v, *p, *r, *s}}}};
  }
  if (cmd == "lss_set_node") {
    if (c.at_end()) return syntax;
    auto v = last_u<std::uint8_t>(c, 0, 0xFF);
    if (!v || (*v > 0x7F && *v < 0xFF)) return syntax;
    return Command{LssCommand{LssSetNode{*v}}};
  }
  if (cmd == "lss_conf_bitrate") {
    if (c.at_end()) return syntax;
    auto sel = inner_u<std::uint8_t>(c, 0, 0);  // only the CiA 301 table
    auto idx = sel ? last_u<std::uint8_t>(c, 0, 9) : std::nullopt;
    if (!idx || *idx == 5) return syntax;
    return Command{LssCommand{LssConfigureBitrate{*sel, *idx}}};
  }
  if (cmd == "lss_activate_bitrate") {
    if (c.at_end()) return syntax;
    auto v = last_u<std::uint16_t>(c, 0, 0xFFFF);
    if (!v) return syntax;
    return Command{LssCommand{LssActivateBitrate{*v}}};
  }
  if (cmd == "lss_store") {
    if (!c.at_end()) return syntax;
    return Command{LssCommand{LssStore{}}};
  }
  if (cmd == "lss_inquire_addr") {
    if (c.at_end()) return Command{LssCommand{LssInquireAddress{}}};
    auto v = last_u<std::uint8_t>(c, 0, 3);
    if (!v) return syntax;
    return Command{LssCommand{LssInquireAddress{*v}}};
  }
  if (cmd == "lss_get_node") {
    if (!c.at_end()) return syntax;
    return Command{LssCommand{LssGetNode{}}};
  }
  if (cmd == "_lss_fastscan") {
    LssFastscan f;
    if (!c.at_end()) {
      auto v = last_u<std::uint16_t>(c, 0, 0xFFFF);
      if (!v) return syntax;
      if (*v != 0) f.timeout_ms = *v;
    }
    return Command{LssCommand{f}};
  }
  if (cmd == "lss_allnodes") {
    LssAllNodes a;
    if (c.at_end()) return Command{LssCommand{a}};
    auto t = parse_u(c.token(), 0, 0xFFFF);
    if (!t) return syntax;
    if (*t != 0) a.timeout_ms = static_cast<std::uint16_t>(*t);
    if (c.at_end()) return Command{LssCommand{a}};
    auto first = inner_u<std::uint8_t>(c, 1, 127);
    if (!first) return syntax;
    a.first_node = *first;
    auto store = parse_u(c.token(), 0, 1);
    if (!store) return syntax;
    a.store = *store == 1;
    if (c.at_end()) return Command{LssCommand{a}};
    std::uint32_t* words[] = {&a.match.vendor_id, &a.match.product_code, &a.match.revision, &a.match.serial};
    for (int i = 0; i < 4; ++i) {
      auto s = inner_u<std::uint8_t>(c, 0, 2);
      auto w = s ? (i < 3 ? inner_u<std::uint32_t>(c, 0, 0xFFFFFFFF) : last_u<std::uint32_t>(c, 0, 0xFFFFFFFF))
                 : std::nullopt;
      if (!w) return syntax;
      a.scan[static_cast<std::size_t>(i)] = static_cast<LssScan>(*s);
      *words[i] = *w;
    }
    return Command{LssCommand{a}};
  }
  return Fail{Error::RequestNotSupported};
}

}  // namespace

Parsed parse_line(std::string_view line, const Defaults& defaults) {
  Parsed out;
  Cursor c(line);
  if (c.at_end()) return out;  // blank or comment only
  out.kind = Parsed::Kind::error;
  auto fail = [&](Error e) {
    out.kind = Parsed::Kind::error;
    out.error = e;
    return out;
  };
  // The mandatory "[<sequence>]".
  const std::string_view seq_tok = c.token();
  if (c.at_end() || seq_tok.size() < 3 || seq_tok.front() != '[' || seq_tok.back() != ']') return fail(Error::Syntax);
  auto seq = parse_u(seq_tok.substr(1, seq_tok.size() - 2), 0, 0xFFFFFFFF);
  if (!seq) return fail(Error::Syntax);
  out.seq = static_cast<std::uint32_t>(*seq);
  out.line.seq = *out.seq;

  // Up to two numbers (node, or net and node), then the command.
  std::uint64_t nums[2] = {};
  int count = 0;
  std::string_view tok;
  for (;;) {
    tok = c.token();
    if (tok.empty()) return fail(Error::Syntax);
    if (tok[0] < '0' || tok[0] > '9') break;
    if (count == 2 || c.at_end()) return fail(Error::Syntax);
    auto v = parse_u(tok, 0, 0xFFFFFFFF);
    if (!v) return fail(Error::Syntax);
    nums[count++] = *v;
  }
  std::uint16_t net = defaults.net;
  std::optional<std::uint8_t> node = defaults.node;
  if (count == 1) {
    if (nums[0] > 127) return fail(Error::UnsupportedNode);
    node = static_cast<std::uint8_t>(nums[0]);
  } else if (count == 2) {
    if (nums[0] > 0xFFFF) return fail(Error::UnsupportedNet);
    if (nums[1] > 127) return fail(Error::UnsupportedNode);
    net = static_cast<std::uint16_t>(nums[0]);
    node = static_cast<std::uint8_t>(nums[1]);
  }
  out.line.net = net;
  const std::string cmd = lowered(tok);
  auto done = [&](Command command, std::uint8_t n = 0) {
    out.kind = Parsed::Kind::command;
    out.line.node = n;
    out.line.command = std::move(command);
    return out;
  };
  // The node a command addresses: 105 without one, 107 below `min`.
  auto need_node = [&](std::uint8_t min) -> std::optional<Error> {
    if (!node) return Error::NoDefaultNode;
    if (*node < min) return Error::UnsupportedNode;
    return std::nullopt;
  };

  if (cmd == "set") {
    if (c.at_end()) return fail(Error::Syntax);
    const std::string what = lowered(c.token());
    if (what == "network") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint16_t>(c, 0, 0xFFFF);
      if (!v) return fail(Error::Syntax);
      return done(SetNetwork{*v});
    }
    if (what == "node") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint8_t>(c, 1, 127);
      if (!v) return fail(Error::Syntax);
      return done(SetNode{*v});
    }
    if (what == "sdo_timeout") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint16_t>(c, 1, 0xFFFF);
      if (!v) return fail(Error::Syntax);
      return done(SetSdoTimeout{*v});
    }
    if (what == "sdo_block") {
      if (c.at_end()) return fail(Error::Syntax);
      auto v = last_u<std::uint8_t>(c, 0, 1);
      if (!v) return fail(Error::Syntax);
      return done(SetSdoBlock{*v == 1});
    }
    return fail(Error::RequestNotSupported);
  }
  if (cmd == "r" || cmd == "read") {
    if (auto e = need_node(1)) return fail(*e);
    if (c.at_end()) return fail(Error::Syntax);
    auto index = inner_u<std::uint16_t>(c, 0, 0xFFFF);
    if (!index) return fail(Error::Syntax);
    auto sub = parse_u(c.token(), 0, 0xFF);
    if (!sub) return fail(Error::Syntax);
    SdoReadCmd r{*index, static_cast<std::uint8_t>(*sub), Datatype::hex};
    if (!c.at_end()) {
      const auto t = c.token();
      if (!c.at_end()) return fail(Error::Syntax);
      auto dt = datatype_from_name(t);
      if (!dt) return fail(Error::Syntax);
      r.type = *dt;
    }
    return done(r, *node);
  }
  if (cmd == "w" || cmd == "write") {
    if (auto e = need_node(1)) return fail(*e);
    if (c.at_end()) return fail(Error::Syntax);
    auto index = inner_u<std::uint16_t>(c, 0, 0xFFFF);
    auto sub = index ? inner_u<std::uint8_t>(c, 0, 0xFF) : std::nullopt;
    if (!sub) return fail(Error::Syntax);
    const auto t = c.token();
    if (t.empty() || c.at_end()) return fail(Error::Syntax);
    auto dt = datatype_from_name(t);
    if (!dt) return fail(Error::Syntax);
    auto data = parse_value(*dt, c.rest());
    if (!data) return fail(Error::Syntax);
    return done(SdoWriteCmd{*index, *sub, *dt, std::move(*data)}, *node);
  }
  auto nmt = [&](canopen::NmtCommand command) {
    if (auto e = need_node(0)) return fail(*e);
    if (!c.at_end()) return fail(Error::Syntax);
    return done(NmtCmd{command}, *node);
  };
  if (cmd == "start") return nmt(canopen::NmtCommand::Start);
  if (cmd == "stop") return nmt(canopen::NmtCommand::Stop);
  if (cmd == "preop" || cmd == "preoperational") return nmt(canopen::NmtCommand::EnterPreOperational);
  if (cmd == "reset") {
    if (auto e = need_node(0)) return fail(*e);
    if (c.at_end()) return fail(Error::Syntax);
    const std::string what = lowered(c.token());
    if (!c.at_end()) return fail(Error::Syntax);
    if (what == "node") return done(NmtCmd{canopen::NmtCommand::ResetNode}, *node);
    if (what == "comm" || what == "communication") return done(NmtCmd{canopen::NmtCommand::ResetCommunication}, *node);
    return fail(Error::Syntax);
  }
  if (cmd == "help") {
    if (c.at_end()) return done(Help{HelpTopic::general});
    const std::string what = lowered(c.token());
    if (!c.at_end()) return fail(Error::Syntax);
    if (what == "datatype") return done(Help{HelpTopic::datatype});
    if (what == "lss") return done(Help{HelpTopic::lss});
    return fail(Error::Syntax);
  }
  if (cmd.starts_with("lss_") || cmd == "_lss_fastscan") {
    auto r = parse_lss(cmd, c);
    if (auto* f = std::get_if<Fail>(&r)) return fail(f->error);
    return done(std::get<Command>(std::move(r)));
  }
  return fail(Error::RequestNotSupported);
}

// ---- canonical text ------------------------------------------------------------

namespace {

std::string value_text(const SdoWriteCmd& w) {
  const auto& d = w.data;
  switch (w.type) {
    case Datatype::hex: return print_value(Datatype::hex, d);
    case Datatype::vs: {
      std::string s = "\"";
      for (auto b : d) {
        s += static_cast<char>(b);
        if (b == '"') s += '"';
      }
      return s + "\"";
    }
    case Datatype::os:
    case Datatype::us:
    case Datatype::d: return print_value(w.type, d);
    case Datatype::r32: {
      float f = 0;
      const auto bits = static_cast<std::uint32_t>(get_le(d));
      std::memcpy(&f, &bits, 4);
      return printf_string("%a", static_cast<double>(f));
    }
    case Datatype::r64: {
      double f = 0;
      const auto bits = get_le(d);
      std::memcpy(&f, &bits, 8);
      return printf_string("%a", f);
    }
    default: break;
  }
  // Integers: hex for x, decimal otherwise (what parse_value reads back).
  const std::uint64_t v = get_le(d);
  switch (w.type) {
    case Datatype::i8: return std::to_string(static_cast<std::int8_t>(v));
    case Datatype::i16: return std::to_string(static_cast<std::int16_t>(v));
    case Datatype::i32: return std::to_string(static_cast<std::int32_t>(v));
    case Datatype::i64: return std::to_string(static_cast<std::int64_t>(v));
    case Datatype::x8:
    case Datatype::x16:
    case Datatype::x32:
    case Datatype::x64: return printf_string("0x%llX", static_cast<unsigned long long>(v));
    default: return std::to_string(v);
  }
}

std::string nmt_text(canopen::NmtCommand c) {
  switch (c) {
    case canopen::NmtCommand::Start: return "start";
    case canopen::NmtCommand::Stop: return "stop";
    case canopen::NmtCommand::EnterPreOperational: return "preop";
    case canopen::NmtCommand::ResetNode: return "reset node";
    case canopen::NmtCommand::ResetCommunication: return "reset comm";
  }
  return "start";
}

std::string lss_text(const LssCommand& l) {
  auto u = [](std::uint64_t v) { return std::to_string(v); };
  return std::visit(
      [&](const auto& x) -> std::string {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, LssSwitchGlobal>) return "lss_switch_glob " + u(x.configuration ? 1 : 0);
        if constexpr (std::is_same_v<T, LssSwitchSelective>)
          return "lss_switch_sel " + u(x.identity.vendor_id) + " " + u(x.identity.product_code) + " " +
                 u(x.identity.revision) + " " + u(x.identity.serial);
        if constexpr (std::is_same_v<T, LssSetNode>) return "lss_set_node " + u(x.node);
        if constexpr (std::is_same_v<T, LssConfigureBitrate>)
          return "lss_conf_bitrate " + u(x.table_selector) + " " + u(x.table_index);
        if constexpr (std::is_same_v<T, LssActivateBitrate>) return "lss_activate_bitrate " + u(x.switch_delay_ms);
        if constexpr (std::is_same_v<T, LssStore>) return "lss_store";
        if constexpr (std::is_same_v<T, LssInquireAddress>)
          return x.lss_sub ? "lss_inquire_addr " + u(*x.lss_sub) : std::string("lss_inquire_addr");
        if constexpr (std::is_same_v<T, LssGetNode>) return "lss_get_node";
        if constexpr (std::is_same_v<T, LssFastscan>) return "_lss_fastscan " + u(x.timeout_ms);
        if constexpr (std::is_same_v<T, LssAllNodes>) {
          std::string s = "lss_allnodes " + u(x.timeout_ms) + " " + u(x.first_node) + " " + u(x.store ? 1 : 0);
          const std::uint32_t words[] = {x.match.vendor_id, x.match.product_code, x.match.revision, x.match.serial};
          for (std::size_t i = 0; i < 4; ++i) s += " " + u(static_cast<unsigned>(x.scan[i])) + " " + u(words[i]);
          return s;
        }
      },
      l);
}

}  // namespace

std::string format_line(const Line& line) {
  std::string s = "[" + std::to_string(line.seq) + "] " + std::to_string(line.net) + " " +
                  std::to_string(line.node) + " ";
  std::visit(
      [&](const auto& x) {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, SdoReadCmd>)
          s += "r " + printf_string("0x%04X", static_cast<unsigned>(x.index)) + " " + std::to_string(x.sub) + " " +
               std::string(datatype_name(x.type));
        if constexpr (std::is_same_v<T, SdoWriteCmd>)
          s += "w " + printf_string("0x%04X", static_cast<unsigned>(x.index)) + " " + std::to_string(x.sub) + " " +
               std::string(datatype_name(x.type)) + " " + value_text(x);
        if constexpr (std::is_same_v<T, NmtCmd>) s += nmt_text(x.command);
        if constexpr (std::is_same_v<T, SetNetwork>) s += "set network " + std::to_string(x.net);
        if constexpr (std::is_same_v<T, SetNode>) s += "set node " + std::to_string(x.node);
        if constexpr (std::is_same_v<T, SetSdoTimeout>) s += "set sdo_timeout " + std::to_string(x.ms);
        if constexpr (std::is_same_v<T, SetSdoBlock>) s += std::string("set sdo_block ") + (x.on ? "1" : "0");
        if constexpr (std::is_same_v<T, Help>)
          s += x.topic == HelpTopic::general ? "help" : x.topic == HelpTopic::datatype ? "help datatype" : "help lss";
        if constexpr (std::is_same_v<T, LssCommand>) s += lss_text(x);
      },
      line.command);
  return s;
}

}  // namespace gateway::ascii
