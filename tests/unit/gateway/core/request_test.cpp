// The roles the request core's commands need (moved here from auth_test's
// RequestKind table) and the API names of NMT commands.
#include "core/request.hpp"

#include "auth/auth.hpp"

#include <gtest/gtest.h>

namespace gateway::core {
namespace {

using canopen::NmtCommand;

TEST(CommandRoles, ReadsViewerWritesOperatorResetsAdmin) {
  EXPECT_EQ(required_role(Operation::sdo_read), Role::Viewer);
  EXPECT_EQ(required_role(Operation::sdo_write), Role::Operator);
  EXPECT_EQ(required_role(Operation::nmt, NmtCommand::Start), Role::Operator);                // 0x01
  EXPECT_EQ(required_role(Operation::nmt, NmtCommand::Stop), Role::Operator);                 // 0x02
  EXPECT_EQ(required_role(Operation::nmt, NmtCommand::EnterPreOperational), Role::Operator);  // 0x80
  EXPECT_EQ(required_role(Operation::nmt, NmtCommand::ResetNode), Role::Admin);               // 0x81
  EXPECT_EQ(required_role(Operation::nmt, NmtCommand::ResetCommunication), Role::Admin);      // 0x82
  // The REST routes' roles (auth::required_role(method, route)) agree.
  EXPECT_EQ(required_role(Operation::rpdo_write), Role::Operator);
  EXPECT_EQ(required_role(Operation::sync), Role::Operator);
  EXPECT_EQ(required_role(Operation::pdo_config_read), Role::Operator);
}

// REST checks the route's role before the core checks the command's: the
// two tables must agree, or a REST caller would be refused by one of them.
TEST(CommandRoles, AgreeWithTheRestRoutes) {
  const std::string node = "/api/v1/networks/{net}/nodes/{node}";
  EXPECT_EQ(auth::required_role("GET", node + "/sdo/{index}/{sub}"), required_role(Operation::sdo_read));
  EXPECT_EQ(auth::required_role("PUT", node + "/sdo/{index}/{sub}"), required_role(Operation::sdo_write));
  EXPECT_EQ(auth::required_role("PUT", node + "/rpdo/{n}"), required_role(Operation::rpdo_write));
  EXPECT_EQ(auth::required_role("POST", node + "/pdo/read"), required_role(Operation::pdo_config_read));
  EXPECT_EQ(auth::required_role("POST", "/api/v1/networks/{net}/sync"), required_role(Operation::sync));
  // The NMT route lets operators in; resets are then refused by the core.
  EXPECT_EQ(auth::required_role("POST", node + "/nmt"), required_role(Operation::nmt, NmtCommand::Start));
}

TEST(CommandRoles, TheCommandDecidesForNmt) {
  EXPECT_EQ(required_role(Command{SdoRead{5, 0x1017, 0, {}}}), Role::Viewer);
  EXPECT_EQ(required_role(Command{SdoWrite{5, 0x1017, 0, {}, 1}}), Role::Operator);
  EXPECT_EQ(required_role(Command{Nmt{0, NmtCommand::Start}}), Role::Operator);
  EXPECT_EQ(required_role(Command{Nmt{0, NmtCommand::ResetNode}}), Role::Admin);
  EXPECT_EQ(required_role(Command{Sync{}}), Role::Operator);
  // Undecided NMT (its body did not decode): the most privileged.
  EXPECT_EQ(required_role(Command{Undecodable{Operation::nmt, 0, "bad", false}}), Role::Admin);
}

TEST(NmtNames, RoundTrip) {
  for (auto c : {NmtCommand::Start, NmtCommand::Stop, NmtCommand::EnterPreOperational, NmtCommand::ResetNode,
                 NmtCommand::ResetCommunication})
    EXPECT_EQ(nmt_command_from_name(nmt_command_name(c)), c);
  EXPECT_EQ(nmt_command_name(NmtCommand::EnterPreOperational), "preop");
  EXPECT_EQ(nmt_command_name(NmtCommand::ResetCommunication), "reset-comm");
  EXPECT_FALSE(nmt_command_from_name("jump"));
}

TEST(SdoProblem, RemoteAbortTimeoutAndLocalFailure) {
  const auto abort = sdo_problem(make_error_code(canopen::SdoAbort::NoSuchObject), true, "ctx");
  EXPECT_EQ(abort.status, 422);
  EXPECT_EQ(abort.title, "SDO abort");
  EXPECT_EQ(abort.abort_code, 0x06020000u);
  EXPECT_EQ(abort.detail, std::string(canopen::sdo_abort_text(0x06020000)) + ": ctx");
  const auto timeout = sdo_problem(make_error_code(canopen::SdoAbort::Timeout), false);
  EXPECT_EQ(timeout.status, 504);
  EXPECT_EQ(timeout.title, "SDO timeout");
  const auto local = sdo_problem(make_error_code(canopen::SdoAbort::GeneralError), false);
  EXPECT_EQ(local.status, 502);
  EXPECT_EQ(local.title, "SDO transfer failed");
}

}  // namespace
}  // namespace gateway::core
