// The ASCII interface's LSS commands (gateway/ascii/ascii_lss.cpp) over a
// real socket against the demo network, whose fourth device starts without
// a node-ID (LSS address 5A1h 8822h 10003h 55000001h): every lss_* command
// through the request core's LSS commands, answers and error codes as
// CANopenNode's gateway writes them (facts B.1), roles as the contract says
// (LSS needs admin, and a refusal says so).
#include "ascii/ascii_lss.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ascii_rig.hpp"

namespace gateway::ascii {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using test::Rig;

const std::string kNewDevice = "0x000005A1 0x00008822 0x00010003 0x55000001";

// An ASCII server whose clients act as admin, with the LSS handler.
struct LssRig : Rig {
  LssRig() : Rig([](ServerConfig& c) { c.role = Role::Admin; }) {
    server->set_lss_handler(make_lss_handler(app->requests()));
  }
};

TEST(AsciiLss, FastscanInquireSetNodeStoreAndTheDeviceBoots) {
  LssRig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] _lss_fastscan 5\n", 1), "[1] " + kNewDevice + "\r\n") << "found and selected";
  EXPECT_EQ(rig.exchange(*c, "[2] lss_get_node\n", 1), "[2] 0xFF\r\n") << "no active node-ID yet";
  EXPECT_EQ(rig.exchange(*c, "[3] lss_inquire_addr\n", 1), "[3] " + kNewDevice + "\r\n");
  EXPECT_EQ(rig.exchange(*c, "[4] lss_inquire_addr 3\n", 1), "[4] 0x55000001\r\n") << "LSSSUB 3: the serial";
  EXPECT_EQ(rig.exchange(*c, "[5] lss_set_node 30\n", 1), "[5] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[6] lss_conf_bitrate 0 2\n", 1), "[6] OK\r\n") << "500 kbit/s, table 0";
  EXPECT_EQ(rig.exchange(*c, "[7] lss_store\n", 1), "[7] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[8] lss_switch_glob 0\n", 1), "[8] OK\r\n");
  EXPECT_TRUE(rig.run_until([&] { return rig.app->cache().node(1, 30) != nullptr; })) << "boot-up as node 30";
  // Nobody unconfigured is left: a fastscan nobody answers is a time-out.
  EXPECT_EQ(rig.exchange(*c, "[9] _lss_fastscan 5\n", 1), "[9] ERROR:103 #Time-out.\r\n");
  rig.log->flush();
  EXPECT_THAT(rig.memlog.text(), HasSubstr("audit: LSS configure node-ID 30 by ascii 127.0.0.1:"));
}

TEST(AsciiLss, SwitchSelectiveByIdentityAndAnAbsentOneTimesOut) {
  LssRig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] lss_switch_sel 0x5A1 0x8822 0x10003 0x55000001\n", 1), "[1] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[2] lss_inquire_addr 0\n", 1), "[2] 0x000005A1\r\n");
  EXPECT_EQ(rig.exchange(*c, "[3] lss_switch_glob 0\n", 1), "[3] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[4] lss_switch_sel 1 2 3 4\n", 1), "[4] ERROR:103 #Time-out.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[5] lss_set_node 0\n", 1), "[5] ERROR:101 #Syntax error.\r\n")
      << "node-ID 0 does not exist (1..127, FFh)";
}

TEST(AsciiLss, AllNodesListsEachAssignmentThenTheCount) {
  LssRig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] lss_allnodes 5 40 1\n", 1),
            "# Node-ID 40 assigned to: " + kNewDevice + "\n# Found 1 nodes, search finished.\n[1] OK\r\n");
  EXPECT_TRUE(rig.run_until([&] { return rig.app->cache().node(1, 40) != nullptr; })) << "boot-up as node 40";
  EXPECT_EQ(rig.exchange(*c, "[2] lss_allnodes 5 41 1\n", 1), "# Found 0 nodes, search finished.\n[2] OK\r\n");
  // Scan types other than fastscan of all four words are not done.
  EXPECT_EQ(rig.exchange(*c, "[3] lss_allnodes 5 41 1 0 0 1 0 0 0 0 0\n", 1),
            "[3] ERROR:100 #Request not supported.\r\n");
}

TEST(AsciiLss, LssNeedsAdminAndTheRefusalNamesTheRoleAndAsciiRole) {
  Rig rig;  // role operator: what the default is once tokens exist or the port is remote
  rig.server->set_lss_handler(make_lss_handler(rig.app->requests()));
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] _lss_fastscan\n", 1), "[1] ERROR:100 #Request not supported. role operator may not do this (needs admin); ascii.role in the gateway's configuration sets the role of ASCII clients\r\n");
  EXPECT_EQ(rig.exchange(*c, "[2] lss_switch_glob 1\n", 1), "[2] ERROR:100 #Request not supported. role operator may not do this (needs admin); ascii.role in the gateway's configuration sets the role of ASCII clients\r\n");
  rig.log->flush();
  EXPECT_THAT(rig.memlog.text(), HasSubstr("auth failure: ascii 127.0.0.1:"));
}

// Issue 28 item 7, contract "ASCII": the commands that address the selected
// device answer ERROR:102 at once when none is selected, as CANopenNode's
// gateway does (it used to wait for the LSS time-out: ERROR:103).
TEST(AsciiLss, CommandsThatNeedASelectedDeviceAreError102AtOnceWithoutOne) {
  LssRig rig;
  auto c = rig.connect();
  const auto started = std::chrono::steady_clock::now();
  EXPECT_EQ(rig.exchange(*c, "[1] lss_store\n", 1), "[1] ERROR:102 #Request not processed due to internal state.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[2] lss_set_node 30\n", 1), "[2] ERROR:102 #Request not processed due to internal state.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[3] lss_conf_bitrate 0 2\n", 1), "[3] ERROR:102 #Request not processed due to internal state.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[4] lss_activate_bitrate 100\n", 1), "[4] ERROR:102 #Request not processed due to internal state.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[5] lss_inquire_addr\n", 1), "[5] ERROR:102 #Request not processed due to internal state.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[6] lss_get_node\n", 1), "[6] ERROR:102 #Request not processed due to internal state.\r\n");
  EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(1)) << "no LSS time-out waited";
  EXPECT_EQ(rig.exchange(*c, "[7] lss_switch_glob 1\n", 1), "[7] OK\r\n");
  EXPECT_THAT(rig.exchange(*c, "[8] lss_get_node\n", 1), StartsWith("[8] 0x")) << "selected: the first to answer";
  EXPECT_EQ(rig.exchange(*c, "[9] lss_switch_glob 0\n", 1), "[9] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[10] lss_store\n", 1), "[10] ERROR:102 #Request not processed due to internal state.\r\n");
}

}  // namespace
}  // namespace gateway::ascii
