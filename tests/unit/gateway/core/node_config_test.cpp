// Run-time node configuration in the request core (gateway/core/node_config.cpp)
// against a fake NodeSettings: contract "Remote configuration and
// maintenance" (GET viewer, PUT/DELETE and the EDS upload admin), the own
// node refused, settings the front end could not decode or for another node
// refused (400, nothing handed on), an EDS/DCF read as `canopen-eds check`
// reads it (400 with "FILE:LINE: reason", nothing handed on), an audit line
// for every change.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/node_settings.hpp"
#include "core/request_core.hpp"
#include "support/fake_networks.hpp"

namespace gateway::core {
namespace {

using ::testing::HasSubstr;
using test_support::FakeNetworks;
using test_support::kOwnNode;

struct FakeSettings final : NodeSettings {
  NodeConfigView node_config(std::uint32_t net, std::uint8_t node) const override {
    NodeConfigView v;
    v.network = net;
    v.node = node;
    v.settings = settings;
    v.source = source;
    return v;
  }
  Result write_node_config(std::uint32_t net, std::uint8_t node, const NodeConfig& s) override {
    ++writes;
    if (refuse) return *refuse;
    settings = s;
    source = "state-dir";
    return node_config(net, node);
  }
  Result write_node_eds(std::uint32_t net, std::uint8_t node, canopen::eds::DeviceDescription d,
                        std::string_view text) override {
    ++writes;
    eds_text = std::string(text);
    product = d.device.product_name;
    source = "state-dir";
    return node_config(net, node);
  }
  Result revert_node_config(std::uint32_t net, std::uint8_t node) override {
    ++writes;
    source = "config";
    return node_config(net, node);
  }
  NodeConfig settings{5, "from-yaml", {}, {}, {}, {}, {}};
  std::string source = "config";
  std::optional<Problem> refuse;
  int writes = 0;
  std::string eds_text, product;
};

// A decoded PUT .../config of node `node` named `name`; the revert (DELETE);
// settings that did not decode, with the parser's reason.
NodeConfigWrite named(std::uint8_t node, std::string name) {
  NodeConfigWrite w;
  w.node = node;
  w.settings.id = node;
  w.settings.name = std::move(name);
  return w;
}
NodeConfigWrite revert(std::uint8_t node) {
  NodeConfigWrite w;
  w.node = node;
  w.revert = true;
  return w;
}
NodeConfigWrite undecoded(std::uint8_t node, std::string why) {
  NodeConfigWrite w;
  w.node = node;
  w.invalid = std::move(why);
  return w;
}

struct Rig {
  Rig() { core.set_node_settings(&settings); }
  Result run(Command cmd, Role role = Role::Admin) {
    Request r;
    r.caller.authenticated = true;
    r.caller.role = role;
    r.caller.who = "alice";
    r.caller.key = "k";
    r.network = 1;
    r.command = std::move(cmd);
    std::optional<Result> out;
    core.execute(std::move(r), [&out](Result res) { out = std::move(res); });
    EXPECT_TRUE(out.has_value()) << "answered at once";
    return out.value_or(Result{Problem{}});
  }
  bool audited(std::string_view part) const {
    for (const auto& l : audit)
      if (l.find(part) != std::string::npos) return true;
    return false;
  }
  FakeNetworks nets;
  auth::TokenStore tokens{{}};
  std::vector<std::string> audit;
  RequestCore core{nets, tokens, {}, [this](const std::string& l) { audit.push_back(l); }};
  FakeSettings settings;
};

const Problem& problem(const Result& r) {
  static const Problem none{};
  if (!std::holds_alternative<Problem>(r)) {
    ADD_FAILURE() << "not a problem";
    return none;
  }
  return std::get<Problem>(r);
}

const char* kGoodEds =
    "[FileInfo]\nFileName=io.eds\n[DeviceInfo]\nVendorName=Test\nProductName=IO\n"
    "[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n"
    "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0x191\n";

// Contract: GET .../config is viewer, PUT and the EDS upload admin.
TEST(RequestCoreNodeConfig, ReadIsViewerChangesAreAdminAndRefusalsChangeNothing) {
  Rig rig;
  const auto view = rig.run(NodeConfigRead{5}, Role::Viewer);
  ASSERT_TRUE(std::holds_alternative<NodeConfigView>(view));
  EXPECT_EQ(std::get<NodeConfigView>(view).source, "config");
  EXPECT_EQ(std::get<NodeConfigView>(view).settings->name, "from-yaml");

  for (const Role r : {Role::Viewer, Role::Operator}) {
    EXPECT_EQ(problem(rig.run(named(5, "x"), r)).status, 403);
    EXPECT_EQ(problem(rig.run(NodeEdsWrite{5, kGoodEds, "io.eds"}, r)).status, 403);
    EXPECT_EQ(problem(rig.run(revert(5), r)).status, 403);
    EXPECT_EQ(problem(rig.run(undecoded(5, "request body: bad"), r)).status, 403) << "bad input gets no cheaper way past";
  }
  EXPECT_EQ(problem(rig.run(NodeConfigRead{5}, Role::None)).status, 401);
  EXPECT_EQ(rig.settings.writes, 0);
  EXPECT_TRUE(rig.audited("auth failure: alice: configuration change net 1 node 5: 403"));

  const auto changed = rig.run(named(5, "x"));
  ASSERT_TRUE(std::holds_alternative<NodeConfigView>(changed));
  EXPECT_EQ(std::get<NodeConfigView>(changed).source, "state-dir");
  EXPECT_EQ(rig.settings.settings.name, "x") << "the typed settings are handed on";
  EXPECT_TRUE(rig.audited("node configuration: alice: net 1 node 5: configuration changed (settings from state-dir)"));
  const auto reverted = rig.run(revert(5));
  ASSERT_TRUE(std::holds_alternative<NodeConfigView>(reverted));
  EXPECT_EQ(std::get<NodeConfigView>(reverted).source, "config");
  EXPECT_TRUE(rig.audited("configuration reverted to the configuration file"));
}

// What the front end could not decode (a bad value: the file parser's
// reason) and what the settings refuse are answered as they are and
// audited; neither changes anything.
TEST(RequestCoreNodeConfig, ARefusedChangeIsAnsweredWithItsReasonAndAudited) {
  Rig rig;
  const std::string why =
      "request body: heartbeat-consumer-ms: 'never' is not auto, 0 (not watched) or a consumer time in ms (1..65535)";
  const auto r = rig.run(undecoded(5, why));
  EXPECT_EQ(problem(r).status, 400);
  EXPECT_EQ(problem(r).detail, why);
  EXPECT_TRUE(rig.audited("node configuration refused: alice: net 1 node 5: configuration changed: 400 request body"));
  EXPECT_EQ(rig.settings.writes, 0) << "nothing reached the settings";

  auto other = named(5, "x");
  other.settings.id = 11;
  EXPECT_EQ(problem(rig.run(other)).detail, "request body: id: 11 is not the node of the path (5)");
  EXPECT_EQ(rig.settings.writes, 0);

  Problem p;
  p.status = 409;
  p.detail = "no state-dir is configured";
  rig.settings.refuse = p;
  EXPECT_EQ(problem(rig.run(named(5, "x"))).detail, p.detail);
  EXPECT_TRUE(rig.audited("node configuration refused: alice: net 1 node 5: configuration changed: 409 no state-dir"));
}

// The gateway's own node has no `nodes:` entry: its settings are the network's.
TEST(RequestCoreNodeConfig, TheOwnNodeIsNotANodeEntry) {
  Rig rig;
  EXPECT_EQ(problem(rig.run(NodeConfigRead{kOwnNode}, Role::Viewer)).status, 400);
  const auto r = rig.run(named(kOwnNode, "x"));
  EXPECT_THAT(problem(r).detail, HasSubstr("is the gateway's own node-ID"));
  EXPECT_EQ(problem(rig.run(NodeConfigRead{0}, Role::Viewer)).status, 400) << "node-IDs are 1..127";
  EXPECT_EQ(rig.settings.writes, 0);
}

// CiA 306 through the gateway's EDS reader, as `canopen-eds check` reads it:
// a file it refuses is 400 "FILE:LINE: reason" and reaches nothing.
TEST(RequestCoreNodeConfig, AnEdsIsReadAsCanopenEdsCheckReadsIt_Cia306) {
  Rig rig;
  const std::string broken = std::string(kGoodEds) + "[6000]\nParameterName=In\nObjectType=0x7\nDataType=0x0005\n"
                                                      "AccessType=ro\nAccessType=rw\n";
  const auto bad = rig.run(NodeEdsWrite{5, broken, "vendor.eds"});
  EXPECT_EQ(problem(bad).status, 400);
  EXPECT_THAT(problem(bad).detail, ::testing::StrEq("vendor.eds:20: key 'AccessType' in [6000] repeated with a different value: 'ro' at line 19, 'rw' here"));
  EXPECT_EQ(rig.settings.writes, 0);
  EXPECT_TRUE(rig.audited("node configuration refused: alice: net 1 node 5: EDS/DCF vendor.eds uploaded: 400"));
  EXPECT_EQ(problem(rig.run(NodeEdsWrite{5, "", ""})).detail, "node5.eds: empty: the body is the EDS or DCF file");

  const auto good = rig.run(NodeEdsWrite{5, kGoodEds, ""});
  ASSERT_TRUE(std::holds_alternative<NodeConfigView>(good));
  EXPECT_EQ(rig.settings.product, "IO") << "the parsed description is handed on";
  EXPECT_EQ(rig.settings.eds_text, kGoodEds) << "and the text to keep";
  EXPECT_TRUE(rig.audited("EDS/DCF node5.eds uploaded (settings from state-dir)"));
}

}  // namespace
}  // namespace gateway::core
