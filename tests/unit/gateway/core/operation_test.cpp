// Issue 26: one descriptor per operation, visited exhaustively. A command
// is never LSS (role admin, one at a time) by falling through a default.
#include "core/operation.hpp"

#include <gtest/gtest.h>

#include <map>
#include <utility>

namespace gateway::core {
namespace {

// A new Command alternative without its own operation_of() is not
// Described, so Command with it fails operation.hpp's static_assert.
struct NewCommand {
  std::uint8_t node = 0;
};
static_assert(!Described<NewCommand>);
static_assert(!EveryCommandDescribed<std::variant<SdoRead, NewCommand>>::value);
static_assert(EveryCommandDescribed<Command>::value);

template <std::size_t... I>
std::vector<Operation> operations_of_every_alternative(std::index_sequence<I...>) {
  return {operation_of(Command{std::variant_alternative_t<I, Command>{}})...};
}

TEST(Operation, EachCommandHasItsOwnAndOnlyTheLssServicesAreLss) {
  const auto ops = operations_of_every_alternative(std::make_index_sequence<std::variant_size_v<Command>>{});
  std::map<Operation, int> count;
  for (auto op : ops) ++count[op];
  // CiA 305's services as the contract offers them: fastscan, configure,
  // assign-all, the device list, and the seven single services.
  EXPECT_EQ(count[Operation::lss], 11);
  EXPECT_EQ(operation_of(Command{SdoWrite{}}), Operation::sdo_write);
  EXPECT_EQ(operation_of(Command{NodeEdsWrite{}}), Operation::config_write);
  EXPECT_EQ(operation_of(Command{ProgramDownload{}}), Operation::program);
  EXPECT_EQ(operation_of(Command{Undecodable{Operation::dcf_read, 5, "bad", false}}), Operation::dcf_read);
  EXPECT_EQ(operation_of(Command{LssInquire{}}), Operation::lss);
}

TEST(Operation, DescriptorsSayTheNodeRuleTheBusRuleAndTheAuditText) {
  EXPECT_EQ(describe(Operation::nmt).node, NodeRule::node_or_all);  // 0 = all nodes (CiA 301 7.2.8.3.1)
  EXPECT_EQ(describe(Operation::sync).node, NodeRule::network);
  EXPECT_EQ(describe(Operation::lss).node, NodeRule::network);
  EXPECT_EQ(describe(Operation::sdo_read).node, NodeRule::node);
  EXPECT_TRUE(describe(Operation::sdo_write).bus_first);
  EXPECT_FALSE(describe(Operation::rpdo_write).bus_first);
  EXPECT_EQ(describe(Operation::dcf_write).text, "DCF apply");
  EXPECT_EQ(describe(Operation::store).text, "store/restore");
}

TEST(Operation, RolesFollowTheDescriptorsNotADefault) {
  EXPECT_EQ(required_role(Command{LssDevices{}}), Role::Admin);
  EXPECT_EQ(required_role(Command{NodeConfigRead{}}), Role::Viewer);
  EXPECT_EQ(required_role(Command{DcfRead{}}), Role::Viewer);
  EXPECT_EQ(required_role(Command{NodeStore{}}), Role::Operator);
  EXPECT_EQ(required_role(Command{PdoConfigRead{}}), Role::Operator);
}

}  // namespace
}  // namespace gateway::core
