#include "http/router.hpp"

#include <gtest/gtest.h>

#include <stdexcept>

using gateway::http::Handler;
using gateway::http::Router;
using Kind = Router::Match::Kind;

namespace {

Handler tagged(int& slot, int tag) {
  return [&slot, tag](const gateway::http::Request&, gateway::http::Responder) { slot = tag; };
}

void call(const Router::Match& m) {
  ASSERT_NE(m.handler, nullptr);
  (*m.handler)(gateway::http::Request{}, nullptr);
}

}  // namespace

TEST(Router, MatchesParametersAndLiterals) {
  Router r;
  int hit = 0;
  r.add("GET", "/api/v1/networks/{net}/nodes/{node}/sdo/{index}/{sub}", tagged(hit, 1));
  r.add("GET", "/api/v1/gateway", tagged(hit, 2));
  auto m = r.match("GET", {"api", "v1", "networks", "1", "nodes", "5", "sdo", "1017", "0"});
  ASSERT_EQ(m.kind, Kind::Found);
  EXPECT_EQ(m.params.at("net"), "1");
  EXPECT_EQ(m.params.at("node"), "5");
  EXPECT_EQ(m.params.at("index"), "1017");
  EXPECT_EQ(m.params.at("sub"), "0");
  call(m);
  EXPECT_EQ(hit, 1);
  EXPECT_EQ(r.match("GET", {"api", "v1", "gateway"}).kind, Kind::Found);
  EXPECT_EQ(r.match("GET", {"api", "v1", "gateway", ""}).kind, Kind::NotFound);  // trailing slash
  EXPECT_EQ(r.match("GET", {"api", "v1"}).kind, Kind::NotFound);
  EXPECT_EQ(r.match("GET", {"api", "v1", "networks", "", "nodes", "5", "sdo", "1017", "0"}).kind, Kind::NotFound);
}

TEST(Router, LiteralBeatsParameter) {
  Router r;
  int hit = 0;
  r.add("GET", "/a/{x}/c", tagged(hit, 1));
  r.add("GET", "/a/b/{y}", tagged(hit, 2));
  r.add("GET", "/a/b/c", tagged(hit, 3));
  call(r.match("GET", {"a", "b", "c"}));
  EXPECT_EQ(hit, 3);
  call(r.match("GET", {"a", "b", "d"}));
  EXPECT_EQ(hit, 2);
  call(r.match("GET", {"a", "z", "c"}));
  EXPECT_EQ(hit, 1);
}

TEST(Router, MethodNotAllowedListsMethods) {
  Router r;
  int hit = 0;
  r.add("GET", "/n/{node}/sdo", tagged(hit, 1));
  r.add("PUT", "/n/{node}/sdo", tagged(hit, 2));
  auto m = r.match("POST", {"n", "5", "sdo"});
  EXPECT_EQ(m.kind, Kind::MethodNotAllowed);
  EXPECT_EQ(m.allow, "GET, HEAD, PUT");
  // HEAD falls back to GET.
  call(r.match("HEAD", {"n", "5", "sdo"}));
  EXPECT_EQ(hit, 1);
}

TEST(Router, RefusesBadPatterns) {
  Router r;
  EXPECT_THROW(r.add("GET", "no/slash", nullptr), std::invalid_argument);
  EXPECT_THROW(r.add("GET", "/a/{}", nullptr), std::invalid_argument);
  EXPECT_THROW(r.add("GET", "/a/{x", nullptr), std::invalid_argument);
  EXPECT_THROW(r.add("GET", "/a/x}", nullptr), std::invalid_argument);
  r.add("GET", "/a/{x}", nullptr);
  EXPECT_THROW(r.add("GET", "/a/{x}", nullptr), std::invalid_argument);
}
