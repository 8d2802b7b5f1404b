// Fuzzes the CiA 309-3 ASCII line parser (gateway/ascii/ascii_command.cpp):
// anyone who reaches the ASCII socket sends these bytes.
// Invariants: nothing crashes or throws; framing does not depend on how the
// bytes are split into reads; a line that parses, formatted back to its
// canonical text (format_line) and parsed again, is the same command
// (a NaN written as r32/r64 stays a NaN; its payload bits may not); a write
// never carries an empty value; an error is one of the codes the parser
// gives; every value prints in every datatype.
// fuzz-libs: gateway_ascii_codec
// fuzz-seeds: tests/fuzz/corpus/ascii_line
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "ascii/ascii_command.hpp"

namespace ascii = gateway::ascii;

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "invariant broken: %s\n", what);
    std::abort();
  }
}

bool is_nan_real(const ascii::SdoWriteCmd& w) {
  if (w.type == ascii::Datatype::r32 && w.data.size() == 4) {
    std::uint32_t bits = 0;
    for (int i = 3; i >= 0; --i) bits = (bits << 8) | w.data[static_cast<std::size_t>(i)];
    float f = 0;
    std::memcpy(&f, &bits, 4);
    return std::isnan(f);
  }
  if (w.type == ascii::Datatype::r64 && w.data.size() == 8) {
    std::uint64_t bits = 0;
    for (int i = 7; i >= 0; --i) bits = (bits << 8) | w.data[static_cast<std::size_t>(i)];
    double f = 0;
    std::memcpy(&f, &bits, 8);
    return std::isnan(f);
  }
  return false;
}

bool same(const ascii::Line& a, const ascii::Line& b) {
  if (a == b) return true;
  const auto* wa = std::get_if<ascii::SdoWriteCmd>(&a.command);
  const auto* wb = std::get_if<ascii::SdoWriteCmd>(&b.command);
  return wa != nullptr && wb != nullptr && a.seq == b.seq && a.net == b.net && a.node == b.node &&
         wa->index == wb->index && wa->sub == wb->sub && wa->type == wb->type && is_nan_real(*wa) && is_nan_real(*wb);
}

bool known_error(ascii::Error e) {
  switch (e) {
    case ascii::Error::RequestNotSupported:
    case ascii::Error::Syntax:
    case ascii::Error::UnsupportedNet:
    case ascii::Error::UnsupportedNode:
    case ascii::Error::NoDefaultNode: return true;
    default: return false;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  constexpr std::size_t kMaxLine = 512;

  // Framing: all at once, or split where the first byte says.
  std::vector<ascii::LineFramer::Item> whole, split;
  ascii::LineFramer a(kMaxLine), b(kMaxLine);
  a.feed(in, whole);
  const std::size_t cut = size == 0 ? 0 : data[0] % (size + 1);
  b.feed(in.substr(0, cut), split);
  b.feed(in.substr(cut), split);
  check(whole.size() == split.size(), "framing independent of the split: count");
  for (std::size_t i = 0; i < whole.size(); ++i) {
    check(whole[i].text == split[i].text && whole[i].too_long == split[i].too_long, "framing independent of the split");
    check(whole[i].text.size() <= kMaxLine, "a line is at most max_line bytes");
  }

  ascii::Defaults defaults;
  if (size > 1 && data[1] % 2 == 0) defaults.node = static_cast<std::uint8_t>(1 + data[1] % 127);
  for (const auto& item : whole) {
    const ascii::Parsed p = ascii::parse_line(item.text, defaults);
    if (p.kind == ascii::Parsed::Kind::error) {
      check(known_error(p.error), "an error code the parser gives");
      continue;
    }
    if (p.kind != ascii::Parsed::Kind::command) continue;
    check(p.seq && *p.seq == p.line.seq, "a command has its sequence number");
    const std::string text = ascii::format_line(p.line);
    const ascii::Parsed again = ascii::parse_line(text, ascii::Defaults{});
    if (again.kind != ascii::Parsed::Kind::command) {
      std::fprintf(stderr, "canonical text does not parse: %s\n", text.c_str());
      std::abort();
    }
    check(same(p.line, again.line), "format_line then parse_line gives the same line");
    if (const auto* w = std::get_if<ascii::SdoWriteCmd>(&p.line.command)) {
      check(!w->data.empty(), "a write carries a value");
      for (std::size_t t = 0; t < ascii::kDatatypeCount; ++t)
        (void)ascii::print_value(static_cast<ascii::Datatype>(t), w->data);
      const std::string hex = ascii::print_value(ascii::Datatype::hex, w->data);
      check(hex.size() == 3 * w->data.size() - 1, "hex: two digits per byte, one space between");
    }
  }
  return 0;
}
