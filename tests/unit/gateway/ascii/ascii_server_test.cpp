// The CiA 309-3 ASCII server (gateway/ascii/ascii_server.cpp) over real
// sockets (TCP on 127.0.0.1, a unix socket) against the whole gateway on the
// simulated demo network (node 5: CiA 402 drive, vendor-ID 5A1h), as cocomm
// or `nc` would use it: contract "CiA 309-3 ASCII interface"; answers as
// facts B.1 (../shared/ref/sparkplug-ascii-lss-facts.md).
#include "ascii/ascii_server.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "app/app.hpp"
#include "ascii_rig.hpp"

namespace gateway::ascii {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::StartsWith;

using test::Client;
using test::Rig;

// ---- commands against the demo devices ---------------------------------------------

TEST(AsciiServer, ReadsRealDemoObjectsInEachDatatype) {
  Rig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] 5 read 0x1018 1 u32\r\n", 1), "[1] 1441\r\n") << "vendor-ID 5A1h";
  EXPECT_EQ(rig.exchange(*c, "[2] 5 r 0x1018 1\n", 1), "[2] A1 05 00 00\r\n") << "hex without a datatype";
  EXPECT_EQ(rig.exchange(*c, "[3] 5 r 0x1018 1 x32\n", 1), "[3] 0x000005A1\r\n");
  EXPECT_EQ(rig.exchange(*c, "[4] 5 r 0x1008 0 vs\n", 1), "[4] \"SD-402\"\r\n");
  EXPECT_EQ(rig.exchange(*c, "[5] 5 r 0x1008 0 d\n", 1), "[5] U0QtNDAy\r\n") << "base64 of SD-402";
  EXPECT_EQ(rig.exchange(*c, "[6] 5 r 0x1018 1 u16\n", 1), "[6] A1 05 00 00\r\n")
      << "4 bytes are not a u16: hex, as CANopenNode";
}

TEST(AsciiServer, WritesGoThroughTheRequestCoreWithAnAuditLine) {
  Rig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] 5 w 0x1017 0 u16 700\n", 1), "[1] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[2] 5 r 0x1017 0 u16\n", 1), "[2] 700\r\n");
  EXPECT_EQ(rig.exchange(*c, "[3] 5 write 0x1017 0 x16 0x3E8 # 1000 ms\n", 1), "[3] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[4] 5 r 0x1017 0 i16\n", 1), "[4] 1000\r\n");
  rig.log->flush();
  EXPECT_THAT(rig.memlog.text(), HasSubstr("SDO write by ascii 127.0.0.1:")) << "audited as every front end is";
  EXPECT_THAT(rig.memlog.text(), HasSubstr("node 5 1017h sub 0 = 700: ok"));
}

TEST(AsciiServer, SdoAbortsAsCanopenNodeFormatsThem) {
  Rig rig;
  auto c = rig.connect();
  EXPECT_THAT(rig.exchange(*c, "[1] 5 r 0x6543 0 u8\n", 1), StartsWith("[1] ERROR:0x06020000 #"));
  EXPECT_THAT(rig.exchange(*c, "[2] 5 w 0x1018 1 u32 1\n", 1), StartsWith("[2] ERROR:0x06010002 #"))
      << "read-only object";
  // A node nobody answers for: the SDO timeout as an abort code; `set
  // sdo_timeout` shortens it for this connection.
  EXPECT_EQ(rig.exchange(*c, "[3] set sdo_timeout 50\n", 1), "[3] OK\r\n");
  EXPECT_THAT(rig.exchange(*c, "[4] 42 r 0x1000 0 u32\n", 1), StartsWith("[4] ERROR:0x05040000 #"));
}

TEST(AsciiServer, NmtCommandsReachTheNode) {
  Rig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] 5 stop\n", 1), "[1] OK\r\n");
  EXPECT_TRUE(rig.run_until([&] { return rig.in_state(5, canopen::NmtState::Stopped); }));
  EXPECT_EQ(rig.exchange(*c, "[2] 5 preop\n", 1), "[2] OK\r\n");
  EXPECT_TRUE(rig.run_until([&] { return rig.in_state(5, canopen::NmtState::PreOperational); }));
  EXPECT_EQ(rig.exchange(*c, "[3] 5 start\n", 1), "[3] OK\r\n");
  EXPECT_TRUE(rig.run_until([&] { return rig.operational(5); }));
  // Reset node needs admin (core::required_role); the rig's role is operator
  // (with tokens or a remote port, the default): the refusal says why.
  EXPECT_EQ(rig.exchange(*c, "[4] 5 reset node\n", 1),
            "[4] ERROR:100 #Request not supported. role operator may not do this (needs admin); ascii.role in the gateway's configuration sets the role of ASCII clients\r\n");
}

TEST(AsciiServer, DefaultsArePerConnection) {
  Rig rig;
  auto a = rig.connect();
  auto b = rig.connect();
  EXPECT_EQ(rig.exchange(*a, "[1] r 0x1018 1 u32\n", 1), "[1] ERROR:105 #No default node set.\r\n");
  EXPECT_EQ(rig.exchange(*a, "[2] set node 5\n", 1), "[2] OK\r\n");
  EXPECT_EQ(rig.exchange(*a, "[3] r 0x1018 1 u32\n", 1), "[3] 1441\r\n");
  EXPECT_EQ(rig.exchange(*b, "[1] r 0x1018 1 u32\n", 1), "[1] ERROR:105 #No default node set.\r\n")
      << "the other connection's default is not this one's";
  EXPECT_EQ(rig.exchange(*a, "[4] set network 2\n", 1), "[4] ERROR:106 #Unsupported net.\r\n") << "one network";
  EXPECT_EQ(rig.exchange(*a, "[5] 2 5 start\n", 1), "[5] ERROR:106 #Unsupported net.\r\n");
  EXPECT_EQ(rig.exchange(*a, "[6] set network 1\n", 1), "[6] OK\r\n");
  EXPECT_EQ(rig.exchange(*a, "[7] 1 5 r 0x1018 1 u32\n", 1), "[7] 1441\r\n");
}

TEST(AsciiServer, MalformedLinesGetTheirErrorAndChangeNothingElse) {
  Rig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[7] 5 r 0x1018 1 u32\n", 1), "[7] 1441\r\n");
  // Without a sequence CANopenNode answers with the previous one.
  EXPECT_EQ(rig.exchange(*c, "5 read 0x1018 1 u32\n", 1), "[7] ERROR:101 #Syntax error.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[8] 5 jump\n", 1), "[8] ERROR:100 #Request not supported.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[9] 200 start\n", 1), "[9] ERROR:107 #Unsupported node.\r\n");
  EXPECT_EQ(rig.exchange(*c, std::string("\x01\xff\x00 garbage\n", 12), 1), "[9] ERROR:101 #Syntax error.\r\n");
  EXPECT_EQ(rig.exchange(*c, "\n# comment only\n", 2), "\r\n\r\n");
  EXPECT_EQ(rig.exchange(*c, "[10] 5 r 0x1018 1 u32\n", 1), "[10] 1441\r\n") << "still served";
}

TEST(AsciiServer, HelpTexts) {
  Rig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] help\n", 1), help_text(HelpTopic::general));
  EXPECT_EQ(rig.exchange(*c, "[2] help datatype\n", 1), help_text(HelpTopic::datatype));
  EXPECT_EQ(rig.exchange(*c, "[3] help lss\n", 1), help_text(HelpTopic::lss));
}

// ---- LSS: parsed here, executed by the handler the gateway sets ---------------------

TEST(AsciiServer, LssWithoutAHandlerIsNotSupported) {
  Rig rig;
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] lss_switch_glob 1\n", 1), "[1] ERROR:100 #Request not supported.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[2] lss_set_node 200\n", 1), "[2] ERROR:101 #Syntax error.\r\n")
      << "arguments are still checked";
}

TEST(AsciiServer, LssCommandsReachTheHandlerTyped) {
  Rig rig;
  std::vector<LssRequest> seen;
  rig.server->set_lss_handler([&](const LssRequest& r, LssReply reply) {
    seen.push_back(r);
    if (std::holds_alternative<LssGetNode>(r.command)) return reply(lss_node_response(r.seq, 5));
    reply(ok_response(r.seq));
    reply(error_response(r.seq, Error::Syntax));  // a second reply is ignored
  });
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] lss_switch_sel 0x5A1 0x402 0x20001 7\n", 1), "[1] OK\r\n");
  EXPECT_EQ(rig.exchange(*c, "[2] 1 0 lss_get_node\n", 1), "[2] 0x05\r\n");
  EXPECT_EQ(rig.exchange(*c, "[3] 2 0 lss_store\n", 1), "[3] ERROR:106 #Unsupported net.\r\n");
  ASSERT_EQ(seen.size(), 2U);
  EXPECT_EQ(seen[0].command, (LssCommand{LssSwitchSelective{{0x5A1, 0x402, 0x20001, 7}}}));
  EXPECT_EQ(seen[0].network, 1U);
  EXPECT_EQ(seen[0].caller.transport, core::Transport::ascii);
  EXPECT_EQ(seen[0].caller.role, Role::Operator);
  EXPECT_EQ(seen[1].seq, 2U);
}

// ---- many clients, slow ones, limits -----------------------------------------------------

TEST(AsciiServer, TwoClientsAtOnceEachGetsItsAnswersInOrder) {
  Rig rig;
  auto a = rig.connect();
  auto b = rig.connect();
  std::string lines_a, lines_b, want_a, want_b;
  for (int i = 1; i <= 20; ++i) {
    lines_a += "[" + std::to_string(i) + "] 5 r 0x1018 1 u32\n";
    want_a += "[" + std::to_string(i) + "] 1441\r\n";
    lines_b += "[" + std::to_string(100 + i) + "] 10 r 0x1008 0 vs\n";
    want_b += "[" + std::to_string(100 + i) + "] \"IO-8822\"\r\n";
  }
  a->send(lines_a);
  b->send(lines_b);
  EXPECT_TRUE(rig.run_until([&] {
    a->poll();
    b->poll();
    return a->answers() >= 20 && b->answers() >= 20;
  }));
  EXPECT_EQ(a->received, want_a);
  EXPECT_EQ(b->received, want_b);
}

TEST(AsciiServer, AClientWaitingForASilentNodeDoesNotHoldUpAnother) {
  Rig rig;
  auto slow = rig.connect();
  auto quick = rig.connect();
  slow->send("[1] set sdo_timeout 3000\n[2] 42 r 0x1000 0 u32\n");
  EXPECT_TRUE(rig.run_until([&] {
    slow->poll();
    return slow->answers() >= 1;
  }));
  EXPECT_EQ(rig.exchange(*quick, "[1] 5 r 0x1018 1 u32\n", 1), "[1] 1441\r\n");
  slow->poll();
  EXPECT_EQ(slow->received, "[1] OK\r\n") << "its read is still waiting for node 42";
  EXPECT_TRUE(rig.run_until([&] {
    slow->poll();
    return slow->answers() >= 2;
  }));
  EXPECT_THAT(slow->received, HasSubstr("[2] ERROR:0x05040000"));
}

TEST(AsciiServer, AClientThatDoesNotReadIsNotBufferedForAndDoesNotBlockOthers) {
  constexpr std::size_t kMaxOutput = 8 * 1024;
  Rig rig([&](ServerConfig& sc) { sc.max_output = kMaxOutput; });
  auto stalled = rig.connect();
  stalled->small_send_buffer();
  auto other = rig.connect();
  // Each help answer is over 1 KiB; 600000 of them are far more than any
  // socket buffer takes, and so are the 8 MB of commands.
  std::string flood;
  for (int i = 0; i < 600000; ++i) flood += "[" + std::to_string(i) + "] help\n";
  std::size_t sent = 0;
  std::size_t most = 0;
  for (int round = 0; round < 300; ++round) {
    sent += stalled->send_some(std::string_view(flood).substr(sent));
    rig.io.run_for(2ms);
    most = std::max(most, rig.server->buffered_output());
  }
  EXPECT_LT(sent, flood.size()) << "the server stopped reading the client that does not read";
  EXPECT_LE(most, kMaxOutput + help_text(HelpTopic::general).size()) << "its answers are not piled up";
  EXPECT_EQ(rig.exchange(*other, "[1] 5 r 0x1018 1 u32\n", 1), "[1] 1441\r\n") << "others are served";
  // It is still connected: once it reads, its answers come.
  EXPECT_TRUE(rig.run_until([&] {
    stalled->poll();
    return stalled->received.size() > help_text(HelpTopic::general).size();
  }));
  EXPECT_EQ(stalled->received.substr(0, help_text(HelpTopic::general).size()), help_text(HelpTopic::general));
  EXPECT_FALSE(stalled->closed);
}

TEST(AsciiServer, AClientThatNeverReadsIsClosedOnceItsOutputStopsMoving) {
  Rig rig([](ServerConfig& sc) {
    sc.max_output = 8 * 1024;
    sc.idle_timeout = 200ms;
  });
  auto stalled = rig.connect();
  std::string flood;
  for (int i = 0; i < 600000; ++i) flood += "[" + std::to_string(i) + "] help\n";
  std::size_t sent = 0;
  EXPECT_TRUE(rig.run_until([&] {
    sent += stalled->send_some(std::string_view(flood).substr(sent));
    return rig.server->clients() == 0;
  })) << "closed: its answers did not move for the idle timeout";
}

TEST(AsciiServer, ALineTooLongIsAnsweredAndTheRestOfItDiscarded) {
  Rig rig([](ServerConfig& sc) { sc.max_line = 64; });
  auto c = rig.connect();
  const std::string long_line = "[7] 5 w 0x2000 0 hex " + std::string(500, 'A') + "\n";
  EXPECT_EQ(rig.exchange(*c, long_line, 1), "[7] ERROR:600 #Running out of memory.\r\n");
  EXPECT_EQ(rig.exchange(*c, "[8] 5 r 0x1018 1 u32\n", 1), "[8] 1441\r\n");
}

TEST(AsciiServer, AnIdleConnectionIsClosed) {
  Rig rig([](ServerConfig& sc) { sc.idle_timeout = 100ms; });
  auto c = rig.connect();
  EXPECT_EQ(rig.exchange(*c, "[1] 5 r 0x1018 1 u32\n", 1), "[1] 1441\r\n");
  EXPECT_TRUE(rig.run_until([&] { return !c->poll(); }, 5s)) << "closed after the idle timeout";
  EXPECT_TRUE(rig.run_until([&] { return rig.server->clients() == 0; }));
}

TEST(AsciiServer, AtMostMaxClients) {
  Rig rig([](ServerConfig& sc) { sc.max_clients = 2; });
  auto a = rig.connect();
  auto b = rig.connect();
  EXPECT_TRUE(rig.run_until([&] { return rig.server->clients() == 2; }));
  auto third = rig.connect();
  EXPECT_TRUE(rig.run_until([&] { return !third->poll(); })) << "closed at once";
  EXPECT_EQ(rig.exchange(*a, "[1] 5 r 0x1018 1 u32\n", 1), "[1] 1441\r\n") << "the others stay";
}

TEST(AsciiServer, AnswersWhatWasSentBeforeTheClientClosedItsSide) {
  Rig rig;
  auto c = rig.connect();
  c->send("[1] 5 r 0x1018 1 u32\n[2] 5 r 0x1018 2 x32\n");
  c->shutdown_write();  // as `nc -N` or a script does
  EXPECT_TRUE(rig.run_until([&] { return !c->poll(); }));
  EXPECT_THAT(c->received, StartsWith("[1] 1441\r\n[2] 0x"));
  EXPECT_EQ(c->answers(), 2U);
}

TEST(AsciiServer, AViewerMayReadButNotWrite) {
  Rig rig([](ServerConfig& sc) { sc.role = Role::Viewer; });
  auto c = rig.connect();
  const std::string before = rig.exchange(*c, "[1] 5 r 0x1017 0 u16\n", 1);
  EXPECT_THAT(before, StartsWith("[1] "));
  EXPECT_EQ(rig.exchange(*c, "[2] 5 w 0x1017 0 u16 1234\n", 1),
            "[2] ERROR:100 #Request not supported. role viewer may not do this (needs operator); ascii.role in the gateway's configuration sets the role of ASCII clients\r\n");
  EXPECT_EQ(rig.exchange(*c, "[3] 5 stop\n", 1),
            "[3] ERROR:100 #Request not supported. role viewer may not do this (needs operator); ascii.role in the gateway's configuration sets the role of ASCII clients\r\n");
  EXPECT_EQ(rig.exchange(*c, "[1] 5 r 0x1017 0 u16\n", 1), before) << "nothing was written";
  EXPECT_TRUE(rig.operational(5)) << "nothing was stopped";
}

TEST(AsciiServer, UnixSocketWithMode0660ReplacedAtStartRemovedAtStop) {
  const std::string path = "/tmp/ascii-test-" + std::to_string(::getpid()) + ".sock";
  {
    // A socket left by an earlier run.
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::copy(path.begin(), path.end(), a.sun_path);
    ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ::close(fd);
  }
  {
    Rig rig([&](ServerConfig& sc) { sc.listen = "unix:" + path; });
    EXPECT_EQ(rig.server->local_address(), "unix:" + path);
    struct stat st {};
    ASSERT_EQ(::stat(path.c_str(), &st), 0);
    EXPECT_TRUE(S_ISSOCK(st.st_mode));
    EXPECT_EQ(st.st_mode & 0777, 0660U);
    auto c = rig.connect();
    ASSERT_TRUE(c->connected());
    EXPECT_EQ(rig.exchange(*c, "[1] 5 r 0x1018 1 u32\n", 1), "[1] 1441\r\n");
  }
  EXPECT_FALSE(std::filesystem::exists(path)) << "removed at stop";
}

}  // namespace
}  // namespace gateway::ascii
