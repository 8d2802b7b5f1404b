// The CiA 309-3 ASCII language (gateway/ascii/ascii_command.cpp) as
// CANopenNode's gateway speaks it, so cocomm and existing scripts work
// unchanged: framing, "[seq]", net/node, every command, every datatype's
// value text both ways, every error code the parser gives, and the answers
// byte for byte. "facts B.1" is ../shared/ref/sparkplug-ascii-lss-facts.md.
#include "ascii/ascii_command.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace gateway::ascii {
namespace {

using canopen::Bytes;
using ::testing::HasSubstr;

Defaults with_node(std::uint8_t node) {
  Defaults d;
  d.node = node;
  return d;
}

Parsed parse(std::string_view text, const Defaults& d = with_node(5)) { return parse_line(text, d); }

Line command(std::string_view text, const Defaults& d = with_node(5)) {
  const Parsed p = parse(text, d);
  EXPECT_EQ(p.kind, Parsed::Kind::command) << text << " -> error " << static_cast<int>(p.error);
  return p.line;
}

// The error code a line gets, 0 when it parses.
int error_of(std::string_view text, const Defaults& d = with_node(5)) {
  const Parsed p = parse(text, d);
  return p.kind == Parsed::Kind::error ? static_cast<int>(p.error) : 0;
}

// The bytes a write's value text gives ("[1] 5 w 0x2000 0 <type> <value>").
std::optional<Bytes> written(std::string_view type, std::string_view value) {
  const Parsed p = parse("[1] 5 w 0x2000 0 " + std::string(type) + " " + std::string(value));
  if (p.kind != Parsed::Kind::command) return std::nullopt;
  return std::get<SdoWriteCmd>(p.line.command).data;
}

template <typename T>
T lss(std::string_view text) {
  const Line l = command(text);
  const auto* c = std::get_if<LssCommand>(&l.command);
  EXPECT_NE(c, nullptr) << text;
  if (c == nullptr || !std::holds_alternative<T>(*c)) {
    ADD_FAILURE() << text << " is not the expected LSS command";
    return T{};
  }
  return std::get<T>(*c);
}

// ---- framing (facts B.1 "Framing") ------------------------------------------------

TEST(AsciiFraming, LinesEndWithLfTheCrIsOptional) {
  LineFramer f(100);
  std::vector<LineFramer::Item> out;
  f.feed("[1] 5 start\r\n[2] 5 st", out);
  f.feed("op\n", out);
  ASSERT_EQ(out.size(), 2U);
  EXPECT_EQ(out[0].text, "[1] 5 start\r");
  EXPECT_EQ(out[1].text, "[2] 5 stop");
  EXPECT_EQ(command(out[0].text).command, Command{NmtCmd{canopen::NmtCommand::Start}}) << "CR is white space";
  EXPECT_EQ(f.buffered(), 0U);
}

TEST(AsciiFraming, AnOverLongLineIsReportedOnceAndItsRestDiscarded) {
  LineFramer f(16);
  std::vector<LineFramer::Item> out;
  f.feed("[1] 5 w 0x2000 0 hex 0102030405", out);
  f.feed("060708090A0B\n[2] 5 start\n", out);
  ASSERT_EQ(out.size(), 2U);
  EXPECT_TRUE(out[0].too_long);
  EXPECT_EQ(out[0].text, "[1] 5 w 0x2000 0");  // its first 16 bytes, for the sequence number
  EXPECT_FALSE(out[1].too_long);
  EXPECT_EQ(out[1].text, "[2] 5 start") << "the next line is read normally";
  EXPECT_EQ(f.buffered(), 0U) << "nothing of the long line kept";
}

TEST(AsciiFraming, EmptyAndCommentLinesAreAnsweredWithAnEmptyLine) {
  EXPECT_EQ(parse("").kind, Parsed::Kind::empty);
  EXPECT_EQ(parse("   \t\r").kind, Parsed::Kind::empty);
  EXPECT_EQ(parse("# a comment [1] 5 start").kind, Parsed::Kind::empty);
  EXPECT_EQ(empty_response(), "\r\n");
}

// ---- sequence, net and node (facts B.1 "Framing", "Net/node parsing") -------------

TEST(AsciiParse, TheSequenceIsMandatory) {
  // CANopenNode answers 101 with the previous sequence number: no seq here.
  for (const char* bad : {"5 read 0x1018 1 u32", "[x] 5 start", "[1 5 start", "[] 5 start", "[-1] 5 start",
                          "[4294967296] 5 start", "[1]", "[1] # only a comment"}) {
    const Parsed p = parse(bad);
    EXPECT_EQ(p.kind, Parsed::Kind::error) << bad;
    EXPECT_EQ(p.error, Error::Syntax) << bad;
    EXPECT_FALSE(p.seq.has_value()) << bad;
  }
  EXPECT_EQ(command("[4294967295] 5 start").seq, 4294967295U);
  EXPECT_EQ(command("[0x10] 5 start").seq, 16U) << "numbers as strtoul base 0";
}

TEST(AsciiParse, OneNumberIsTheNodeTwoAreNetAndNode) {
  const Line one = command("[1] 7 start");
  EXPECT_EQ(one.net, 1U);
  EXPECT_EQ(one.node, 7U);
  const Line two = command("[2] 3 9 start");
  EXPECT_EQ(two.net, 3U);
  EXPECT_EQ(two.node, 9U);
  Defaults d = with_node(11);
  d.net = 2;
  const Line none = command("[3] start", d);
  EXPECT_EQ(none.net, 2U) << "set network's default";
  EXPECT_EQ(none.node, 11U) << "set node's default";
  EXPECT_EQ(error_of("[4] 1 2 3 start"), 101) << "at most two numbers";
  EXPECT_EQ(error_of("[4] 5"), 101) << "a number cannot end the line";
}

TEST(AsciiParse, NetAndNodeErrorCodes) {
  EXPECT_EQ(error_of("[1] 128 start"), 107);
  EXPECT_EQ(error_of("[1] 1 128 start"), 107);
  EXPECT_EQ(error_of("[1] 65536 5 start"), 106);
  EXPECT_EQ(error_of("[1] start", Defaults{}), 105) << "no default node set";
  EXPECT_EQ(error_of("[1] r 0x1018 1", Defaults{}), 105);
  EXPECT_EQ(error_of("[1] r", Defaults{}), 105) << "as CANopenNode: the node is checked before the arguments";
  EXPECT_EQ(error_of("[1] 0 r 0x1018 1"), 107) << "SDO needs node 1..127";
  EXPECT_EQ(command("[1] 0 start").node, 0U) << "NMT node 0: all nodes";
}

TEST(AsciiParse, CommandsAreCaseInsensitive) {
  const Line l = command("[1] 5 READ 0X1018 1 U32");
  EXPECT_EQ(l.command, (Command{SdoReadCmd{0x1018, 1, Datatype::u32}}));
  EXPECT_EQ(command("[2] 5 Reset Communication").command, Command{NmtCmd{canopen::NmtCommand::ResetCommunication}});
  EXPECT_EQ(command("[3] HELP LSS").command, Command{Help{HelpTopic::lss}});
}

TEST(AsciiParse, UnknownCommandsAreNotSupportedOtherMistakesAreSyntax) {
  EXPECT_EQ(error_of("[1] 5 frobnicate"), 100);
  // Non-standard or not implemented in CANopenNode either (facts B.1 "Not implemented").
  for (const char* cmd : {"[1] led", "[1] log", "[1] info version", "[1] 5 enable guarding", "[1] init 2",
                          "[1] set heartbeat 100", "[1] set command_timeout 10"})
    EXPECT_EQ(error_of(cmd), 100) << cmd;
  EXPECT_EQ(error_of("[1] set"), 101);
  EXPECT_EQ(error_of("[1] set foo 1"), 100);
}

// ---- read / write --------------------------------------------------------------------

TEST(AsciiParse, ReadWithAndWithoutDatatype) {
  EXPECT_EQ(command("[1] 5 r 0x1018 1").command, (Command{SdoReadCmd{0x1018, 1, Datatype::hex}}))
      << "hex without a datatype";
  EXPECT_EQ(command("[1] 5 read 4120 0x01 vs").command, (Command{SdoReadCmd{0x1018, 1, Datatype::vs}}));
  EXPECT_EQ(command("[1] 5 r 0x1018 010 u8 # comment").command, (Command{SdoReadCmd{0x1018, 8, Datatype::u8}}))
      << "leading 0 is octal, as strtoul";
  for (const char* bad : {"[1] 5 r", "[1] 5 r 0x1018", "[1] 5 r 0x10000 0", "[1] 5 r 0x1018 256",
                          "[1] 5 r 0x1018 1 u33", "[1] 5 r 0x1018 1 u32 extra", "[1] 5 r 0x1018 1 t"})
    EXPECT_EQ(error_of(bad), 101) << bad;
}

TEST(AsciiParse, EveryDatatypeOfTheTable) {
  // facts B.1 "Datatypes": CANopenNode's table, and nothing else (no t/td).
  const std::vector<std::string> names = {"hex", "b",   "i8",  "i16", "i32", "i64", "u8", "u16", "u32", "u64",
                                          "x8",  "x16", "x32", "x64", "r32", "r64", "vs", "os",  "us",  "d"};
  ASSERT_EQ(names.size(), kDatatypeCount);
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto t = datatype_from_name(names[i]);
    ASSERT_TRUE(t.has_value()) << names[i];
    EXPECT_EQ(static_cast<std::size_t>(*t), i);
    EXPECT_EQ(datatype_name(*t), names[i]);
  }
  EXPECT_FALSE(datatype_from_name("t"));
  EXPECT_FALSE(datatype_from_name("td"));
  EXPECT_FALSE(datatype_from_name("i24"));
  EXPECT_EQ(datatype_size(Datatype::i64), 8U);
  EXPECT_FALSE(datatype_size(Datatype::vs));
}

TEST(AsciiValues, IntegersAsStrtolWithRangeChecks) {
  EXPECT_EQ(written("b", "1"), (Bytes{1}));
  EXPECT_EQ(written("u8", "255"), (Bytes{0xFF}));
  EXPECT_EQ(written("u8", "256"), std::nullopt);
  EXPECT_EQ(written("u16", "0x1234"), (Bytes{0x34, 0x12})) << "little-endian on the bus";
  EXPECT_EQ(written("u16", "010"), (Bytes{8, 0}));
  EXPECT_EQ(written("u32", "4294967295"), (Bytes{0xFF, 0xFF, 0xFF, 0xFF}));
  EXPECT_EQ(written("u32", "4294967296"), std::nullopt);
  EXPECT_EQ(written("u64", "18446744073709551615"), (Bytes(8, 0xFF)));
  EXPECT_EQ(written("u64", "18446744073709551616"), std::nullopt);
  EXPECT_EQ(written("x8", "0x7f"), (Bytes{0x7F}));
  EXPECT_EQ(written("x16", "0xBEEF"), (Bytes{0xEF, 0xBE}));
  EXPECT_EQ(written("x32", "0x000005A1"), (Bytes{0xA1, 0x05, 0, 0}));
  EXPECT_EQ(written("x64", "0x0102030405060708"), (Bytes{8, 7, 6, 5, 4, 3, 2, 1}));
  EXPECT_EQ(written("i8", "-128"), (Bytes{0x80}));
  EXPECT_EQ(written("i8", "128"), std::nullopt);
  EXPECT_EQ(written("i16", "-2"), (Bytes{0xFE, 0xFF}));
  EXPECT_EQ(written("i16", "-0x10"), (Bytes{0xF0, 0xFF})) << "strtol takes a sign before 0x";
  EXPECT_EQ(written("i32", "-2147483648"), (Bytes{0, 0, 0, 0x80}));
  EXPECT_EQ(written("i32", "2147483648"), std::nullopt);
  EXPECT_EQ(written("i64", "-9223372036854775808"), (Bytes{0, 0, 0, 0, 0, 0, 0, 0x80}));
  EXPECT_EQ(written("u16", "-1"), std::nullopt);
  EXPECT_EQ(written("u16", "12a"), std::nullopt);
  EXPECT_EQ(written("u16", "1 2"), std::nullopt) << "the value is the last token";
  EXPECT_EQ(written("u16", "100 # heartbeat"), (Bytes{100, 0})) << "a comment may follow";
}

TEST(AsciiValues, RealsAsStrtofAndStrtod) {
  EXPECT_EQ(written("r32", "1.5"), (Bytes{0, 0, 0xC0, 0x3F}));
  EXPECT_EQ(written("r32", "-2e0"), (Bytes{0, 0, 0, 0xC0}));
  EXPECT_EQ(written("r64", "0.1"), (Bytes{0x9A, 0x99, 0x99, 0x99, 0x99, 0x99, 0xB9, 0x3F})) << "double precision";
  EXPECT_EQ(written("r32", "1.5x"), std::nullopt);
}

TEST(AsciiValues, VisibleStringOneWordOrQuoted) {
  auto text = [](std::string_view s) { return Bytes(s.begin(), s.end()); };
  EXPECT_EQ(written("vs", "save"), text("save"));
  EXPECT_EQ(written("vs", "\"hello world\""), text("hello world"));
  EXPECT_EQ(written("vs", "\"say \"\"hi\"\"\" # comment"), text("say \"hi\"")) << "\"\" is a quote";
  EXPECT_EQ(written("vs", "a\"\"b"), text("a\"b"));
  EXPECT_EQ(written("vs", "a#b"), text("a#b")) << "a '#' inside a word is text, as in CANopenNode";
  EXPECT_EQ(written("vs", "\"a # b\""), text("a # b"));
  EXPECT_EQ(written("vs", "\"unclosed"), std::nullopt);
  EXPECT_EQ(written("vs", "a\"b"), std::nullopt) << "a lone quote inside a word";
  EXPECT_EQ(written("vs", "\"a\"b"), std::nullopt) << "white space must follow the closing quote";
  EXPECT_EQ(written("vs", "two words"), std::nullopt);
  EXPECT_EQ(written("vs", "\"\""), std::nullopt) << "an empty value is not written";
  EXPECT_EQ(written("vs", "# only a comment"), std::nullopt);
}

TEST(AsciiValues, OctetUnicodeAndDomainAsBase64) {
  EXPECT_EQ(written("os", "AQID"), (Bytes{1, 2, 3}));
  EXPECT_EQ(written("d", "SGVsbG8="), (Bytes{'H', 'e', 'l', 'l', 'o'}));
  EXPECT_EQ(written("d", "SGVsbA=="), (Bytes{'H', 'e', 'l', 'l'}));
  EXPECT_EQ(written("us", "QQBCAA== # AB in UTF-16LE"), (Bytes{'A', 0, 'B', 0}));
  EXPECT_EQ(written("d", "SGV*"), std::nullopt);
  EXPECT_EQ(written("d", "SGVs bG8="), std::nullopt) << "one line, one word";
}

TEST(AsciiValues, HexBytesOptionallySpaceSeparated) {
  EXPECT_EQ(written("hex", "01 0203 4"), (Bytes{1, 2, 3, 4}));
  EXPECT_EQ(written("hex", "a1B2 # comment"), (Bytes{0xA1, 0xB2}));
  EXPECT_EQ(written("hex", "0G"), std::nullopt);
  EXPECT_EQ(written("hex", "# nothing"), std::nullopt);
}

TEST(AsciiParse, WriteNeedsTypeAndValue) {
  const Line l = command("[9] 2 5 w 0x1017 0 u16 1000");
  EXPECT_EQ(l.seq, 9U);
  EXPECT_EQ(l.net, 2U);
  EXPECT_EQ(l.node, 5U);
  EXPECT_EQ(l.command, (Command{SdoWriteCmd{0x1017, 0, Datatype::u16, Bytes{0xE8, 0x03}}}));
  for (const char* bad : {"[1] 5 w", "[1] 5 w 0x1017", "[1] 5 w 0x1017 0", "[1] 5 w 0x1017 0 u16",
                          "[1] 5 write 0x1017 0 u17 5", "[1] 5 w 0x1017 300 u16 5"})
    EXPECT_EQ(error_of(bad), 101) << bad;
}

// ---- NMT, set, help ------------------------------------------------------------------

TEST(AsciiParse, NmtCommands) {
  using canopen::NmtCommand;
  EXPECT_EQ(command("[1] 5 start").command, Command{NmtCmd{NmtCommand::Start}});
  EXPECT_EQ(command("[1] 5 stop").command, Command{NmtCmd{NmtCommand::Stop}});
  EXPECT_EQ(command("[1] 5 preop").command, Command{NmtCmd{NmtCommand::EnterPreOperational}});
  EXPECT_EQ(command("[1] 5 preoperational").command, Command{NmtCmd{NmtCommand::EnterPreOperational}});
  EXPECT_EQ(command("[1] 5 reset node").command, Command{NmtCmd{NmtCommand::ResetNode}});
  EXPECT_EQ(command("[1] 5 reset comm").command, Command{NmtCmd{NmtCommand::ResetCommunication}});
  EXPECT_EQ(command("[1] 5 reset communication").command, Command{NmtCmd{NmtCommand::ResetCommunication}});
  for (const char* bad : {"[1] 5 start now", "[1] 5 reset", "[1] 5 reset all", "[1] 5 reset node 1"})
    EXPECT_EQ(error_of(bad), 101) << bad;
}

TEST(AsciiParse, SetCommandsAndTheirRanges) {
  EXPECT_EQ(command("[1] set network 2").command, Command{SetNetwork{2}});
  EXPECT_EQ(command("[1] set node 127").command, Command{SetNode{127}});
  EXPECT_EQ(command("[1] set sdo_timeout 1000").command, Command{SetSdoTimeout{1000}});
  EXPECT_EQ(command("[1] set sdo_block 1").command, Command{SetSdoBlock{true}});
  EXPECT_EQ(command("[1] set node 5", Defaults{}).command, Command{SetNode{5}}) << "needs no default node";
  for (const char* bad : {"[1] set node 0", "[1] set node 128", "[1] set sdo_timeout 0", "[1] set sdo_timeout 65536",
                          "[1] set sdo_block 2", "[1] set network 65536", "[1] set node", "[1] set node 5 6"})
    EXPECT_EQ(error_of(bad), 101) << bad;
  const Defaults d;
  EXPECT_EQ(d.sdo_timeout_ms, 500U) << "facts B.1: 500 ms by default";
  EXPECT_FALSE(d.sdo_block) << "block transfer off by default";
}

TEST(AsciiParse, HelpTopics) {
  EXPECT_EQ(command("[1] help").command, Command{Help{HelpTopic::general}});
  EXPECT_EQ(command("[1] help datatype").command, Command{Help{HelpTopic::datatype}});
  EXPECT_EQ(command("[1] help lss").command, Command{Help{HelpTopic::lss}});
  EXPECT_EQ(error_of("[1] help me"), 101);
  for (auto t : {HelpTopic::general, HelpTopic::datatype, HelpTopic::lss}) {
    const auto h = help_text(t);
    EXPECT_EQ(h.front(), '\n');
    EXPECT_TRUE(h.ends_with("\r\n"));
    EXPECT_EQ(h.find("\r\n"), h.size() - 2) << "only the last line ends in CR LF";
  }
  EXPECT_THAT(std::string(help_text(HelpTopic::datatype)), HasSubstr("x8 x16 x32 x64"));
  EXPECT_THAT(std::string(help_text(HelpTopic::lss)), HasSubstr("lss_allnodes"));
}

// ---- LSS (facts B.1 "LSS commands"): parsed into typed values -------------------------

TEST(AsciiLss, EveryCommandWithItsArguments) {
  EXPECT_EQ(lss<LssSwitchGlobal>("[1] lss_switch_glob 1"), LssSwitchGlobal{true});
  EXPECT_EQ(lss<LssSwitchGlobal>("[1] lss_switch_glob 0"), LssSwitchGlobal{false});
  EXPECT_EQ(lss<LssSwitchSelective>("[1] lss_switch_sel 0x5A1 0x402 0x20001 12345"),
            (LssSwitchSelective{{0x5A1, 0x402, 0x20001, 12345}}));
  EXPECT_EQ(lss<LssSetNode>("[1] lss_set_node 20"), LssSetNode{20});
  EXPECT_EQ(lss<LssSetNode>("[1] lss_set_node 255"), LssSetNode{0xFF}) << "0xFF: unconfigured";
  EXPECT_EQ(lss<LssConfigureBitrate>("[1] lss_conf_bitrate 0 2"), (LssConfigureBitrate{0, 2}));
  EXPECT_EQ(lss_bitrate_kbit(2), 500U);
  EXPECT_EQ(lss_bitrate_kbit(8), 10U);
  EXPECT_EQ(lss<LssActivateBitrate>("[1] lss_activate_bitrate 500"), LssActivateBitrate{500});
  EXPECT_EQ(lss<LssStore>("[1] lss_store"), LssStore{});
  EXPECT_EQ(lss<LssInquireAddress>("[1] lss_inquire_addr"), LssInquireAddress{});
  EXPECT_EQ(lss<LssInquireAddress>("[1] lss_inquire_addr 3"), LssInquireAddress{3});
  EXPECT_EQ(lss<LssGetNode>("[1] lss_get_node"), LssGetNode{});
  EXPECT_EQ(lss<LssFastscan>("[1] _lss_fastscan"), LssFastscan{100}) << "default 100 ms";
  EXPECT_EQ(lss<LssFastscan>("[1] _lss_fastscan 0"), LssFastscan{100});
  EXPECT_EQ(lss<LssFastscan>("[1] _lss_fastscan 250"), LssFastscan{250});
  const Line on_net = command("[1] 3 0 lss_store");
  EXPECT_EQ(on_net.net, 3U) << "LSS commands take [<net>]";
}

TEST(AsciiLss, AllNodesDefaultsAndFullForm) {
  const LssAllNodes plain = lss<LssAllNodes>("[1] lss_allnodes");
  EXPECT_EQ(plain.timeout_ms, 100U);
  EXPECT_EQ(plain.first_node, 2U) << "facts B.1: start node 2, store on";
  EXPECT_TRUE(plain.store);
  EXPECT_EQ(plain.scan, (std::array<LssScan, 4>{}));
  EXPECT_EQ(lss<LssAllNodes>("[1] lss_allnodes 200").timeout_ms, 200U);
  const LssAllNodes mid = lss<LssAllNodes>("[1] lss_allnodes 200 10 0");
  EXPECT_EQ(mid.first_node, 10U);
  EXPECT_FALSE(mid.store);
  const LssAllNodes full = lss<LssAllNodes>("[1] lss_allnodes 50 20 1 2 0x5A1 0 0 1 0 0 0");
  EXPECT_EQ(full.timeout_ms, 50U);
  EXPECT_EQ(full.scan[0], LssScan::match);
  EXPECT_EQ(full.match.vendor_id, 0x5A1U);
  EXPECT_EQ(full.scan[1], LssScan::scan);
  EXPECT_EQ(full.scan[2], LssScan::ignore);
}

TEST(AsciiLss, ArgumentErrorsAreSyntaxErrors) {
  for (const char* bad :
       {"[1] lss_switch_glob", "[1] lss_switch_glob 2", "[1] lss_switch_sel 1 2 3", "[1] lss_switch_sel 1 2 3 4 5",
        "[1] lss_set_node 128", "[1] lss_set_node 254", "[1] lss_set_node", "[1] lss_conf_bitrate 1 2",
        "[1] lss_conf_bitrate 0 5", "[1] lss_conf_bitrate 0 10", "[1] lss_conf_bitrate 2",
        "[1] lss_activate_bitrate 65536", "[1] lss_store now", "[1] lss_inquire_addr 4", "[1] lss_get_node 1",
        "[1] _lss_fastscan 65536", "[1] lss_allnodes 100 0 1", "[1] lss_allnodes 100 5", "[1] lss_allnodes 100 5 2",
        "[1] lss_allnodes 100 5 1 3 0 0 0 0 0 0 0", "[1] lss_allnodes 100 5 1 0 0 0 0 0 0 0"})
    EXPECT_EQ(error_of(bad), 101) << bad;
  EXPECT_EQ(error_of("[1] lss_frobnicate"), 100);
}

// ---- canonical text --------------------------------------------------------------------

TEST(AsciiParse, AFormattedLineParsesToTheSameLine) {
  for (const char* text :
       {"[1] 5 r 0x1018 1 u32", "[2] 3 9 w 0x2000 1 vs \"a \"\"b\"\" #c\"", "[3] 5 w 0x2000 0 r32 1.5",
        "[4] 5 w 0x2000 0 r64 -0.1", "[5] 5 w 0x2000 0 i64 -9223372036854775808", "[6] 5 w 0x2000 0 x16 0xBEEF",
        "[7] 5 w 0x2000 0 d SGVsbG8=", "[8] 5 w 0x2000 0 hex 01 02 0", "[9] 0 reset comm", "[10] set sdo_block 1",
        "[11] help lss", "[12] lss_allnodes 50 20 1 2 0x5A1 0 0 1 0 0 0", "[13] lss_inquire_addr",
        "[14] lss_switch_sel 1 2 3 4", "[15] _lss_fastscan", "[16] 5 w 0x2000 0 b 1"}) {
    const Line l = command(text);
    const std::string again = format_line(l);
    const Parsed p = parse(again, Defaults{});
    ASSERT_EQ(p.kind, Parsed::Kind::command) << text << " -> " << again;
    EXPECT_EQ(p.line, l) << text << " -> " << again;
  }
}

// ---- printing a value read (facts B.1: CANopenNode's formats) ---------------------------

TEST(AsciiPrint, NumbersWhenTheSizeMatchesHexOtherwise) {
  EXPECT_EQ(print_value(Datatype::u32, Bytes{0xA1, 0x05, 0, 0}), "1441");
  EXPECT_EQ(print_value(Datatype::u32, Bytes{0xA1, 0x05}), "A1 05") << "2 bytes are not a u32";
  EXPECT_EQ(print_value(Datatype::hex, Bytes{0xA1, 0x05, 0, 0}), "A1 05 00 00");
  EXPECT_EQ(print_value(Datatype::b, Bytes{1}), "1");
  EXPECT_EQ(print_value(Datatype::i8, Bytes{0x80}), "-128");
  EXPECT_EQ(print_value(Datatype::i16, Bytes{0xFE, 0xFF}), "-2");
  EXPECT_EQ(print_value(Datatype::i32, Bytes{0, 0, 0, 0x80}), "-2147483648");
  EXPECT_EQ(print_value(Datatype::i64, Bytes{0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF}), "-1");
  EXPECT_EQ(print_value(Datatype::u64, Bytes(8, 0xFF)), "18446744073709551615");
  EXPECT_EQ(print_value(Datatype::x8, Bytes{0x0A}), "0x0A");
  EXPECT_EQ(print_value(Datatype::x16, Bytes{0xEF, 0xBE}), "0xBEEF");
  EXPECT_EQ(print_value(Datatype::x32, Bytes{0xA1, 0x05, 0, 0}), "0x000005A1");
  EXPECT_EQ(print_value(Datatype::x64, Bytes{1, 0, 0, 0, 0, 0, 0, 0}), "0x0000000000000001");
  EXPECT_EQ(print_value(Datatype::r32, Bytes{0, 0, 0xC0, 0x3F}), "1.5") << "%g";
  EXPECT_EQ(print_value(Datatype::r64, Bytes{0x9A, 0x99, 0x99, 0x99, 0x99, 0x99, 0xB9, 0x3F}), "0.1");
  EXPECT_EQ(print_value(Datatype::hex, Bytes{}), "");
}

TEST(AsciiPrint, StringsQuotedAndBase64) {
  const std::string raw("IO \"8822\"\r\0x", 12);
  EXPECT_EQ(print_value(Datatype::vs, Bytes(raw.begin(), raw.end())), "\"IO \"\"8822\"\"x\"")
      << "quotes doubled, CR and NUL left out";
  EXPECT_EQ(print_value(Datatype::d, Bytes{'H', 'e', 'l', 'l', 'o'}), "SGVsbG8=");
  EXPECT_EQ(print_value(Datatype::os, Bytes{'H', 'e', 'l', 'l'}), "SGVsbA==");
  EXPECT_EQ(print_value(Datatype::us, Bytes{1, 2, 3}), "AQID");
}

TEST(AsciiPrint, ChunkedPrintingGivesTheSameText) {
  Bytes big(10000);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<std::uint8_t>(i * 7);
  for (auto t : {Datatype::d, Datatype::hex, Datatype::vs}) {
    std::string whole = print_value(t, big);
    std::string pieces;
    ValuePrinter p(t, big.size());
    for (std::size_t pos = 0; pos < big.size(); pos += 3 * 100) {
      const std::size_t n = std::min<std::size_t>(300, big.size() - pos);
      p.print(std::span<const std::uint8_t>(big.data() + pos, n), pos + n == big.size(), pieces);
    }
    EXPECT_EQ(pieces, whole) << datatype_name(t);
  }
}

// ---- answers (facts B.1 "Responses"; CANopenNode with error descriptions) --------------

TEST(AsciiResponses, FormattedAsCanopenNodeDoes) {
  EXPECT_EQ(ok_response(7), "[7] OK\r\n");
  EXPECT_EQ(error_response(3, Error::Syntax), "[3] ERROR:101 #Syntax error.\r\n");
  EXPECT_EQ(error_response(4, Error::NoDefaultNode), "[4] ERROR:105 #No default node set.\r\n");
  EXPECT_EQ(abort_response(5, 0x06020000).rfind("[5] ERROR:0x06020000 #", 0), 0U);
  EXPECT_TRUE(abort_response(5, 0x06020000).ends_with("\r\n"));
  EXPECT_EQ(lss_node_response(1, 5), "[1] 0x05\r\n");
  EXPECT_EQ(lss_word_response(2, 0x5A1), "[2] 0x000005A1\r\n");
  EXPECT_EQ(lss_identity_response(3, {0x5A1, 0x402, 0x20001, 7}), "[3] 0x000005A1 0x00000402 0x00020001 0x00000007\r\n");
  EXPECT_EQ(lss_assigned_line(20, {1, 2, 3, 4}), "# Node-ID 20 assigned to: 0x00000001 0x00000002 0x00000003 0x00000004\n");
  EXPECT_EQ(lss_allnodes_finished(9, 2), "# Found 2 nodes, search finished.\n[9] OK\r\n");
}

TEST(AsciiResponses, EveryErrorCodeHasItsMeaning) {
  // facts B.1 "Internal error codes".
  const std::vector<std::pair<int, std::string>> codes = {
      {100, "Request not supported."}, {101, "Syntax error."}, {102, "Request not processed due to internal state."},
      {103, "Time-out."}, {104, "No default net set."}, {105, "No default node set."}, {106, "Unsupported net."},
      {107, "Unsupported node."}, {200, "Lost guarding message."}, {201, "Lost connection."},
      {202, "Heartbeat started."}, {203, "Heartbeat lost."}, {204, "Wrong NMT state."}, {205, "Boot-up."},
      {300, "Error passive."}, {301, "Bus off."}, {303, "CAN buffer overflow."}, {304, "CAN init."},
      {305, "CAN active."}, {400, "PDO already used."}, {401, "PDO length exceeded."},
      {501, "LSS manufacturer error."}, {502, "LSS node-ID not supported."}, {503, "LSS bit-rate not supported."},
      {504, "LSS parameter storing failed."}, {505, "LSS media error."}, {600, "Running out of memory."}};
  for (const auto& [code, text] : codes) {
    EXPECT_EQ(error_text(static_cast<Error>(code)), text) << code;
    EXPECT_EQ(error_response(1, static_cast<Error>(code)), "[1] ERROR:" + std::to_string(code) + " #" + text + "\r\n");
  }
}

}  // namespace
}  // namespace gateway::ascii
