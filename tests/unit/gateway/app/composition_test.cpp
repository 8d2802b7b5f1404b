// compose_networks (gateway/app/composition.cpp): the configuration becomes
// one NetworkUnit per network, its channel opened - the simulated bus
// handed to the unit like a SocketCAN channel.
#include "app/composition.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "canopen/socketcan/channel.hpp"
#include "app/demo_devices.hpp"
#include "sim/asio_memory_bus.hpp"
#include "sim/simulator.hpp"

namespace gateway {
namespace {

Config demo_config() {
  CliOptions cli;
  cli.demo = true;
  return merge(Config{}, cli);
}

TEST(Composition, ADemoNetworkIsOneUnitWhoseChannelIsTheSimulatedBus) {
  boost::asio::io_context io;
  Logger log(LogLevel::Error);
  auto c = compose_networks(io, demo_config(), log);
  ASSERT_EQ(c.units.size(), 1U);
  const NetworkUnit& u = *c.units[0];
  EXPECT_EQ(u.number, 1U);
  EXPECT_EQ(u.label, "net 1 demo");
  EXPECT_EQ(c.monitor, nullptr) << "no SocketCAN network, no link monitor";
  ASSERT_NE(u.link.memory_gateway, nullptr);
  EXPECT_EQ(u.link.channel, u.link.memory_gateway.get()) << "the unit uses the gateway's end of the bus";
  EXPECT_EQ(u.channel, u.tapped.get()) << "through the trace tap (issue 18), so every frame passes it";
  ASSERT_NE(u.link.simulator, nullptr);
  EXPECT_EQ(u.link.simulator->size(), demo_node_configs().size()) << "the demo devices on the other end";
  EXPECT_EQ(u.link.simulator->unconfigured(), 1U) << "and one that waits for LSS (issue 16, CiA 305)";
  EXPECT_EQ(u.descriptions.size(), demo_node_configs().size());
  EXPECT_EQ(u.cfg.nodes.size(), demo_node_configs().size()) << "the node list is the demo's";
}

TEST(Composition, ABadEdsIsAConfigErrorBeforeAnyChannelIsOpened) {
  const auto dir = std::filesystem::temp_directory_path() / ("composition_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto eds = dir / "broken.eds";
  std::ofstream(eds) << "[DeviceInfo\nthis is not an EDS\n";
  Config cfg;
  NetworkConfig net;
  net.interface = "no-such-can-interface";  // opening it would be CanUnavailable
  NodeConfig node;
  node.id = 5;
  node.eds = eds.string();
  net.nodes.push_back(node);
  cfg.networks.push_back(net);
  boost::asio::io_context io;
  Logger log(LogLevel::Error);
  EXPECT_THROW(compose_networks(io, cfg, log), ConfigError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace gateway
