// The OpenAPI document (gateway/rest/openapi.json) against the routes the
// server really has: no route undescribed, no operation without a route,
// every operation with responses and (unless public) the bearer scheme and
// the role auth.cpp asks for, every path parameter declared, every $ref
// resolvable. And it is served, without a token, as application/json.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <utility>

#include "auth/auth.hpp"
#include "http/request_checks.hpp"
#include "rest_rig.hpp"

namespace gateway {
namespace {

namespace json = boost::json;
using test::RestRig;
using Operation = std::pair<std::string, std::string>;  // (method, path)

constexpr const char* kMethods[] = {"get", "put", "post", "delete", "patch", "head", "options", "trace"};

json::object document() {
  boost::system::error_code ec;
  auto v = json::parse(openapi_document(), ec);
  EXPECT_FALSE(ec) << "openapi.json is not JSON: " << ec.message();
  if (ec || !v.is_object()) return {};
  return v.as_object();
}

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// "#/components/parameters/net" -> the value, or nullptr.
const json::value* resolve(const json::object& doc, std::string_view ref) {
  if (ref.substr(0, 2) != "#/") return nullptr;  // only local refs are used
  const json::value* cur = nullptr;
  const json::object* obj = &doc;
  std::string_view rest = ref.substr(2);
  while (obj != nullptr) {
    const auto slash = rest.find('/');
    const auto key = rest.substr(0, slash);
    cur = obj->if_contains(key);
    if (cur == nullptr || slash == std::string_view::npos) return cur;
    rest = rest.substr(slash + 1);
    obj = cur->if_object();
  }
  return nullptr;
}

const json::object* deref(const json::object& doc, const json::value& v) {
  const auto* o = v.if_object();
  if (o == nullptr) return nullptr;
  if (const auto* r = o->if_contains("$ref"); r != nullptr && r->is_string()) {
    const auto* target = resolve(doc, r->as_string());
    return target != nullptr ? target->if_object() : nullptr;
  }
  return o;
}

std::set<Operation> described(const json::object& doc) {
  std::set<Operation> out;
  for (const auto& [path, item] : doc.at("paths").as_object())
    for (const char* m : kMethods)
      if (item.as_object().contains(m)) out.emplace(upper(m), std::string(path));
  return out;
}

std::set<Operation> served() {
  RestRig rig;
  std::set<Operation> out;
  for (const auto& r : rig.server->routes()) out.insert(r);
  out.emplace("GET", "/api/v1/events");  // the server's own WebSocket path
  return out;
}

TEST(OpenApi, IsAnOpenApi3DocumentWithInfoAndPaths) {
  const auto doc = document();
  ASSERT_TRUE(doc.contains("openapi"));
  EXPECT_THAT(std::string(doc.at("openapi").as_string()), ::testing::StartsWith("3."));
  const auto& info = doc.at("info").as_object();
  EXPECT_FALSE(info.at("title").as_string().empty());
  EXPECT_FALSE(info.at("version").as_string().empty());
  EXPECT_FALSE(doc.at("paths").as_object().empty());
  const auto& bearer = doc.at("components").at("securitySchemes").at("bearerAuth").as_object();
  EXPECT_EQ(bearer.at("type").as_string(), "http");
  EXPECT_EQ(bearer.at("scheme").as_string(), "bearer");
}

TEST(OpenApi, DescribesExactlyTheServedOperations) {
  const auto doc = document();
  const auto have = served();
  const auto told = described(doc);
  for (const auto& op : have) EXPECT_TRUE(told.count(op)) << "not described: " << op.first << " " << op.second;
  for (const auto& op : told) EXPECT_TRUE(have.count(op)) << "no such route: " << op.first << " " << op.second;
  EXPECT_GE(have.size(), 14U);  // 11 REST routes, /metrics, this document, the event stream
}

TEST(OpenApi, EveryOperationHasResponsesSecurityAndItsPathParameters) {
  const auto doc = document();
  const json::array* global_security = nullptr;
  if (const auto* g = doc.if_contains("security")) global_security = g->if_array();
  for (const auto& [path_key, item_value] : doc.at("paths").as_object()) {
    const std::string path(path_key);
    const auto& item = item_value.as_object();
    // Names of the {params} in the template.
    std::set<std::string> templ;
    for (std::size_t p = path.find('{'); p != std::string::npos; p = path.find('{', p + 1))
      templ.insert(path.substr(p + 1, path.find('}', p) - p - 1));
    std::set<std::string> path_level;
    if (const auto* ps = item.if_contains("parameters"))
      for (const auto& pv : ps->as_array())
        if (const auto* p = deref(doc, pv); p != nullptr && p->at("in").as_string() == "path")
          path_level.insert(std::string(p->at("name").as_string()));
    for (const char* m : kMethods) {
      const auto* opv = item.if_contains(m);
      if (opv == nullptr) continue;
      const auto& op = opv->as_object();
      const std::string where = upper(m) + " " + path;
      SCOPED_TRACE(where);
      EXPECT_TRUE(op.contains("operationId"));
      EXPECT_TRUE(op.contains("summary") || op.contains("description"));

      // Responses: at least one, each with a description; a 2xx or 101.
      ASSERT_TRUE(op.contains("responses"));
      const auto& responses = op.at("responses").as_object();
      EXPECT_FALSE(responses.empty());
      bool success = false;
      for (const auto& [code, rv] : responses) {
        const auto* r = deref(doc, rv);
        ASSERT_NE(r, nullptr) << "response " << code << " does not resolve";
        EXPECT_TRUE(r->contains("description")) << code;
        success = success || code.starts_with("2") || code == "101";
      }
      EXPECT_TRUE(success);

      // Security: public operations say so with an empty list; the others
      // need the bearer scheme and state the role auth.cpp requires.
      const Role need = auth::required_role(upper(m), path);
      const json::array* security = global_security;
      if (const auto* s = op.if_contains("security")) security = s->if_array();
      ASSERT_NE(security, nullptr) << "no security stated";
      if (need == Role::None) {
        EXPECT_TRUE(security->empty()) << "public operation with security";
        EXPECT_FALSE(op.contains("x-required-role") && op.at("x-required-role") != "none");
      } else {
        bool bearer = false;
        for (const auto& req : *security)
          bearer = bearer || req.as_object().contains("bearerAuth");
        EXPECT_TRUE(bearer) << "needs the bearer scheme";
        ASSERT_TRUE(op.contains("x-required-role"));
        EXPECT_EQ(op.at("x-required-role").as_string(), to_string(need));
        EXPECT_TRUE(responses.contains("401"));
        EXPECT_TRUE(responses.contains("403"));
      }

      // Every template parameter is declared (path item or operation), in: path, required.
      std::set<std::string> declared = path_level;
      if (const auto* ps = op.if_contains("parameters")) {
        for (const auto& pv : ps->as_array()) {
          const auto* p = deref(doc, pv);
          ASSERT_NE(p, nullptr) << "parameter does not resolve";
          if (p->at("in").as_string() == "path") {
            EXPECT_TRUE(p->contains("required") && p->at("required").as_bool());
            declared.insert(std::string(p->at("name").as_string()));
          }
        }
      }
      EXPECT_EQ(declared, templ);
    }
  }
}

// Every "$ref" in the document points at something that exists.
void check_refs(const json::object& doc, const json::value& v, std::string& where) {
  if (const auto* o = v.if_object()) {
    for (const auto& [k, child] : *o) {
      if (k == "$ref" && child.is_string()) {
        EXPECT_NE(resolve(doc, child.as_string()), nullptr) << "dangling $ref " << child.as_string() << " in " << where;
        continue;
      }
      const auto len = where.size();
      where += "/" + std::string(k);
      check_refs(doc, child, where);
      where.resize(len);
    }
  } else if (const auto* a = v.if_array()) {
    for (const auto& child : *a) check_refs(doc, child, where);
  }
}

TEST(OpenApi, EveryRefResolves) {
  const auto doc = document();
  std::string where;
  check_refs(doc, doc, where);
}

// What the server refuses before any route runs (request_checks.hpp) is
// part of every operation's contract.
TEST(OpenApi, BrowserRefusalsAreDocumented) {
  const auto doc = document();
  for (const auto& [path, item] : doc.at("paths").as_object()) {
    for (const char* m : kMethods) {
      const auto* op = item.as_object().if_contains(m);
      if (op == nullptr) continue;
      const auto& responses = op->at("responses").as_object();
      SCOPED_TRACE(upper(m) + " " + std::string(path));
      EXPECT_TRUE(responses.contains("421")) << "foreign Host";
      if (http::is_state_changing(upper(m))) {
        EXPECT_TRUE(responses.contains("403")) << "foreign Origin";
        EXPECT_TRUE(responses.contains("415")) << "body neither JSON nor protobuf";
      }
    }
  }
}

TEST(OpenApi, ServedAsJsonWithoutAToken) {
  // Auth on with one token: the document stays public, the API does not.
  RestRig rig({}, [](Config& c) {
    c.http.auth = true;
    c.http.tokens.push_back({"ops", Role::Operator, auth::sha256_hex("secret")});
  });
  auto r = rig.request("GET", "/api/v1/openapi.json");
  ASSERT_EQ(r.status, 200) << r.body.substr(0, 200);
  EXPECT_EQ(r.content_type, "application/json");
  ASSERT_TRUE(r.json().is_object()) << "not JSON";
  EXPECT_EQ(r.json().as_object().at("openapi"), json::parse(openapi_document()).as_object().at("openapi"));
  EXPECT_EQ(rig.request("GET", "/api/v1/gateway").status, 401);
  EXPECT_EQ(rig.request("GET", "/api/v1/gateway", {}, {"Authorization: Bearer secret"}).status, 200);
}

}  // namespace
}  // namespace gateway
