// The header checks that stand between browsers (and smugglers) and the
// API: Host and Origin policy, framing, body media type. The same rules over
// a real socket are in server_test.cpp.
#include "http/request_checks.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

namespace gateway::http {
namespace {

using Verdict = OriginPolicy::HostVerdict;

OriginPolicy policy(std::string listen, std::vector<std::string> names = {}, std::vector<std::string> origins = {},
                    std::string machine = "plc-gw-7") {
  return OriginPolicy({std::move(listen), std::move(names), std::move(origins), std::move(machine)});
}

TEST(ParseHost, NamesIpLiteralsAndPorts) {
  auto h = parse_host("LocalHost:8080");
  ASSERT_TRUE(h);
  EXPECT_EQ(h->host, "localhost");
  EXPECT_EQ(h->port, 8080);
  EXPECT_FALSE(h->ip_literal);

  h = parse_host("localhost.");  // the absolute DNS name is the same name
  ASSERT_TRUE(h);
  EXPECT_EQ(h->host, "localhost");
  EXPECT_FALSE(h->port);

  h = parse_host("127.0.0.1");
  ASSERT_TRUE(h);
  EXPECT_TRUE(h->ip_literal);
  EXPECT_EQ(h->host, "127.0.0.1");

  h = parse_host("[0:0::1]:443");  // canonical IPv6 text
  ASSERT_TRUE(h);
  EXPECT_TRUE(h->ip_literal);
  EXPECT_EQ(h->host, "[::1]");
  EXPECT_EQ(h->port, 443);

  h = parse_host("gw.example:");  // an empty port is allowed by RFC 3986
  ASSERT_TRUE(h);
  EXPECT_FALSE(h->port);

  for (const char* bad : {"", "a b", "::1", "[::1", "[::1]x", "[fe80::1%25eth0]", "host:99999", "host:8o",
                          "user@host", "host/path", "h%41st", "a:1:2", ":80"})
    EXPECT_FALSE(parse_host(bad)) << bad;
}

TEST(ParseOrigin, SchemeHostAndEffectivePort) {
  auto o = parse_origin("HTTPS://GW.example");
  ASSERT_TRUE(o);
  EXPECT_EQ(o->canonical(), "https://gw.example:443");
  o = parse_origin("http://127.0.0.1:8080");
  ASSERT_TRUE(o);
  EXPECT_EQ(o->canonical(), "http://127.0.0.1:8080");
  for (const char* bad : {"null", "file://", "chrome-extension://abc", "http://", "http://a/b", "http://a?x",
                          "http://u@a", "gw.example"})
    EXPECT_FALSE(parse_origin(bad)) << bad;
}

// Each way of making the end of a request ambiguous (request smuggling).
TEST(Framing, OnlyOneUnambiguousWayToFindTheBody) {
  const auto bad = [](HeaderFields f, unsigned version = 11) { return framing_error(f, version).has_value(); };
  EXPECT_FALSE(bad({{"Host", "a"}, {"Transfer-Encoding", "chunked"}}));
  EXPECT_FALSE(bad({{"Host", "a"}, {"transfer-encoding", " Chunked "}}));
  EXPECT_FALSE(bad({{"Content-Length", "5"}, {"content-length", "5"}}));  // the same value twice
  EXPECT_FALSE(bad({{"Content-Length", "5, 5"}}));
  EXPECT_FALSE(bad({{"Host", "a"}}, 10));
  EXPECT_FALSE(bad({}));

  EXPECT_TRUE(bad({{"Transfer-Encoding", "xchunked"}}));
  EXPECT_TRUE(bad({{"Transfer-Encoding", "chunked, identity"}}));
  EXPECT_TRUE(bad({{"Transfer-Encoding", "identity, chunked"}}));
  EXPECT_TRUE(bad({{"Transfer-Encoding", "gzip"}}));
  EXPECT_TRUE(bad({{"Transfer-Encoding", "chunked"}, {"Transfer-Encoding", "chunked"}}));
  EXPECT_TRUE(bad({{"Transfer-Encoding", "chunked"}, {"Content-Length", "3"}}));
  EXPECT_TRUE(bad({{"Transfer-Encoding", "chunked"}}, 10));
  EXPECT_TRUE(bad({{"Content-Length", "5"}, {"Content-Length", "6"}}));
  EXPECT_TRUE(bad({{"Content-Length", "5, 6"}}));
  EXPECT_TRUE(bad({{"Content-Length", "-1"}}));
  EXPECT_TRUE(bad({{"Content-Length", ""}}));
  EXPECT_TRUE(bad({{"Authorization", "Bearer a"}, {"authorization", "Bearer b"}}));
  EXPECT_TRUE(bad({{"Host", "a"}, {"HOST", "b"}}));
}

TEST(BodyType, OnlyTheApiMediaTypes) {
  EXPECT_TRUE(acceptable_body_type("application/json", true));
  EXPECT_TRUE(acceptable_body_type("Application/JSON; charset=utf-8", true));
  EXPECT_TRUE(acceptable_body_type("application/x-protobuf", true));
  EXPECT_TRUE(acceptable_body_type(std::nullopt, false));  // POST .../sync without a body
  // What an HTML form or a "simple" cross-site fetch can send.
  EXPECT_FALSE(acceptable_body_type("text/plain", true));
  EXPECT_FALSE(acceptable_body_type("text/plain;charset=UTF-8", true));
  EXPECT_FALSE(acceptable_body_type("application/x-www-form-urlencoded", true));
  EXPECT_FALSE(acceptable_body_type("multipart/form-data; boundary=x", true));
  EXPECT_FALSE(acceptable_body_type("text/plain", false));
  EXPECT_FALSE(acceptable_body_type(std::nullopt, true));
  // A route's own extra types (an upload route: application/octet-stream).
  const std::vector<std::string> upload = {"application/octet-stream"};
  EXPECT_TRUE(acceptable_body_type("Application/Octet-Stream", true, upload));
  EXPECT_FALSE(acceptable_body_type("application/octet-stream", true));
  EXPECT_FALSE(acceptable_body_type("text/plain", true, upload));
  EXPECT_FALSE(acceptable_body_type("application/jsonx", true));

  EXPECT_TRUE(is_state_changing("POST"));
  EXPECT_TRUE(is_state_changing("PUT"));
  EXPECT_TRUE(is_state_changing("DELETE"));
  EXPECT_TRUE(is_state_changing("PATCH"));
  EXPECT_FALSE(is_state_changing("GET"));
  EXPECT_FALSE(is_state_changing("HEAD"));
  EXPECT_FALSE(is_state_changing("OPTIONS"));
}

TEST(OriginPolicy, LoopbackListenerKnowsItsLocalNames) {
  const auto p = policy("127.0.0.1");
  for (const char* own : {"127.0.0.1:8080", "127.0.0.1", "localhost:8080", "LOCALHOST", "localhost.:8080",
                          "[::1]:8080"})
    EXPECT_EQ(p.check_host(own, 11), Verdict::Own) << own;
  // DNS rebinding: the attacker's name now resolves to 127.0.0.1.
  EXPECT_EQ(p.check_host("rebind.attacker.example:8080", 11), Verdict::Foreign);
  EXPECT_EQ(p.check_host("localhost.attacker.example", 11), Verdict::Foreign);
  EXPECT_EQ(p.check_host("plc-gw-7", 11), Verdict::Foreign);  // the machine's name only on a wildcard listener
  EXPECT_EQ(p.check_host("10.0.0.7:8080", 11), Verdict::Foreign);
  EXPECT_EQ(p.check_host(std::nullopt, 11), Verdict::Missing);
  EXPECT_EQ(p.check_host(std::nullopt, 10), Verdict::Own);  // HTTP/1.0 has no Host
  EXPECT_EQ(p.check_host("a b", 11), Verdict::Malformed);

  EXPECT_EQ(policy("::1").check_host("[::1]:8080", 11), Verdict::Own);
  EXPECT_EQ(policy("::1").check_host("localhost", 11), Verdict::Own);
  EXPECT_EQ(policy("localhost").check_host("127.0.0.1:80", 11), Verdict::Own);
}

TEST(OriginPolicy, SpecificAddressAndHostNames) {
  const auto p = policy("192.168.10.5", {"gw.plant.example", "10.9.8.7"});
  EXPECT_EQ(p.check_host("192.168.10.5:8443", 11), Verdict::Own);
  EXPECT_EQ(p.check_host("GW.Plant.Example:8443", 11), Verdict::Own);
  EXPECT_EQ(p.check_host("10.9.8.7", 11), Verdict::Own);  // e.g. a NAT address
  EXPECT_EQ(p.check_host("localhost", 11), Verdict::Foreign);
  EXPECT_EQ(p.check_host("192.168.10.6", 11), Verdict::Foreign);
  EXPECT_EQ(p.check_host("plc-gw-7", 11), Verdict::Foreign);
}

TEST(OriginPolicy, WildcardListenerTakesAnyIpLiteralAndTheMachineName) {
  for (const char* any : {"0.0.0.0", "::"}) {
    const auto p = policy(any, {"gw.plant.example"});
    EXPECT_EQ(p.check_host("10.1.2.3:8080", 11), Verdict::Own) << any;
    EXPECT_EQ(p.check_host("[fd00::5]:8080", 11), Verdict::Own) << any;
    EXPECT_EQ(p.check_host("Plc-Gw-7:8080", 11), Verdict::Own) << any;
    EXPECT_EQ(p.check_host("localhost:8080", 11), Verdict::Own) << any;
    EXPECT_EQ(p.check_host("gw.plant.example", 11), Verdict::Own) << any;
    EXPECT_EQ(p.check_host("rebind.attacker.example", 11), Verdict::Foreign) << any;
  }
}

TEST(OriginPolicy, OwnOriginIsSchemeHostAndPortOfTheHost) {
  const auto p = policy("127.0.0.1", {}, {"https://scada.example"});
  EXPECT_TRUE(p.origin_allowed("http://127.0.0.1:8080", "127.0.0.1:8080", false));
  EXPECT_TRUE(p.origin_allowed("http://LOCALHOST:8080", "localhost:8080", false));
  EXPECT_TRUE(p.origin_allowed("https://localhost", "localhost", true));      // default ports
  EXPECT_TRUE(p.origin_allowed("http://localhost:80", "localhost", false));
  EXPECT_TRUE(p.origin_allowed("https://scada.example", "127.0.0.1:8080", false));  // allowed-origins
  EXPECT_TRUE(p.origin_allowed("https://scada.example:443", "127.0.0.1:8080", false));

  EXPECT_FALSE(p.origin_allowed("http://evil.example", "127.0.0.1:8080", false));
  EXPECT_FALSE(p.origin_allowed("http://127.0.0.1:9000", "127.0.0.1:8080", false));  // another local service
  EXPECT_FALSE(p.origin_allowed("https://127.0.0.1:8080", "127.0.0.1:8080", false));  // scheme differs
  EXPECT_FALSE(p.origin_allowed("http://localhost:8080", "127.0.0.1:8080", false));   // host differs
  EXPECT_FALSE(p.origin_allowed("null", "127.0.0.1:8080", false));                    // sandboxed frame, file
  EXPECT_FALSE(p.origin_allowed("http://scada.example", "127.0.0.1:8080", false));    // not the listed scheme
  EXPECT_FALSE(p.origin_allowed("http://127.0.0.1:8080", std::nullopt, false));      // HTTP/1.0 without Host

  const auto any = policy("127.0.0.1", {}, {"*"});
  EXPECT_TRUE(any.origin_allowed("http://evil.example", "127.0.0.1:8080", false));
}

TEST(OriginPolicy, BadSettingsAreRefused) {
  EXPECT_THROW(policy("gw.example"), std::invalid_argument);
  EXPECT_THROW(policy("127.0.0.1", {"gw.example:8080"}), std::invalid_argument);
  EXPECT_THROW(policy("127.0.0.1", {"a b"}), std::invalid_argument);
  EXPECT_THROW(policy("127.0.0.1", {}, {"scada.example"}), std::invalid_argument);
  EXPECT_THROW(policy("127.0.0.1", {}, {"https://scada.example/"}), std::invalid_argument);
  EXPECT_NO_THROW(policy("0.0.0.0", {}, {}, ""));  // no machine name
}

}  // namespace
}  // namespace gateway::http
