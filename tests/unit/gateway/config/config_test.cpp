// Configuration file + command line (gateway/config/config.cpp): every key
// reaches its field, flags win, and every mistake is one line naming file,
// line, key and reason while nothing else is assumed.
#include "config/config.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <boost/json/serialize.hpp>

namespace gateway {
namespace {

using ::testing::ContainsRegex;
using ::testing::HasSubstr;
using ::testing::Not;
using namespace std::chrono_literals;

const std::string kEds = std::string(CANOPEN_SOURCE_DIR) + "/deploy/eds/cia402-drive.eds";
const std::string kIo = std::string(CANOPEN_SOURCE_DIR) + "/deploy/eds/cia401-io-module.eds";

std::string config_error(const std::string& yaml, const std::string& file = "gw.yaml") {
  try {
    parse_config(yaml, file);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a ConfigError for:\n" << yaml;
  return {};
}

std::string merge_error(const Config& c, const CliOptions& cli) {
  try {
    merge(c, cli);
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a ConfigError";
  return {};
}

TEST(Config, FullFileReachesEveryField) {
  const std::string yaml = R"(
gateway:
  id: plant-7
  node-id: 100
  log-level: debug
  state-dir: /tmp/gw-state
networks:
  - interface: can0
    bitrate: 500000
    heartbeat-ms: 500
    sync: {period-us: 10000, counter-overflow: 16, window-us: 8000}
    time: {produce: true, period-ms: 2000}
    nodes:
      - id: 5
        name: drive
        eds: )" + kEds + R"(
        heartbeat-consumer-ms: 1500
        boot: {configure: true, start: true}
      - id: 0x0A
        dcf: )" + kIo + R"(
        guarding: {guard-time-ms: 100, life-time-factor: 3}
  - interface: can1
    node-id: 1
mqtt:
  uri: tcp://broker:1883
  client-id: gw
  username: u
  password: p
  format: protobuf
  qos: {default: 1, tpdo: 0}
  heartbeat: false
  heartbeat-min-interval-ms: 5000
  queue: {dir: q, max-bytes: 1048576, max-messages: 1000}
http:
  listen: 0.0.0.0:8443
  allowed-origins: [https://scada.example]
  tokens:
    - {name: ops, role: operator, sha256: 9F86D081884C7D659A2FEAA0C55AD015A3BF4F1B2B0B822CD15D6C15B0F00A08}
)";
  const Config c = parse_config(yaml, "/etc/gw/gw.yaml");
  EXPECT_EQ(c.gateway_id, "plant-7");
  EXPECT_EQ(c.log_level, LogLevel::Debug);
  EXPECT_EQ(c.state_dir, "/tmp/gw-state");
  ASSERT_EQ(c.networks.size(), 2U);
  const auto& n1 = c.networks[0];
  EXPECT_EQ(n1.interface, "can0");
  EXPECT_EQ(n1.bitrate, 500000U);
  EXPECT_EQ(n1.node_id, 100);  // gateway.node-id is the default per network
  EXPECT_EQ(n1.heartbeat_producer, 500ms);
  EXPECT_EQ(n1.sync.period, 10000us);
  EXPECT_EQ(n1.sync.counter_overflow, 16);
  EXPECT_EQ(n1.sync.window, 8000us);
  EXPECT_TRUE(n1.time.produce);
  EXPECT_EQ(n1.time.period, 2000ms);
  ASSERT_EQ(n1.nodes.size(), 2U);
  EXPECT_EQ(n1.nodes[0].id, 5);
  EXPECT_EQ(n1.nodes[0].name, "drive");
  EXPECT_EQ(n1.nodes[0].eds, kEds);
  EXPECT_EQ(n1.nodes[0].heartbeat_consumer, 1500ms);
  ASSERT_TRUE(n1.nodes[0].boot);
  EXPECT_TRUE(n1.nodes[0].boot->configure);
  EXPECT_TRUE(n1.nodes[0].boot->start);
  EXPECT_TRUE(n1.nodes[0].boot->check_identity);
  EXPECT_EQ(n1.nodes[1].id, 10);
  EXPECT_EQ(n1.nodes[1].guarding.guard_time, 100ms);
  EXPECT_EQ(n1.nodes[1].guarding.life_time_factor, 3);
  EXPECT_FALSE(n1.nodes[1].boot);
  EXPECT_EQ(c.networks[1].node_id, 1);
  EXPECT_TRUE(c.mqtt.enabled);
  EXPECT_EQ(c.mqtt.server_uri, "tcp://broker:1883");
  EXPECT_EQ(c.mqtt.client_id, "gw");
  EXPECT_EQ(c.mqtt.format, PayloadFormat::Protobuf);
  EXPECT_EQ(c.mqtt.qos_for(EventKind::Tpdo), 0);
  EXPECT_EQ(c.mqtt.qos_for(EventKind::Heartbeat), 1);  // default: 1 applies to every kind not named
  EXPECT_FALSE(c.mqtt.heartbeat);
  EXPECT_EQ(c.mqtt.heartbeat_min_interval, 5000ms);
  EXPECT_EQ(c.mqtt.queue.dir, "/etc/gw/q");  // relative to the file
  EXPECT_EQ(c.mqtt.queue.max_bytes, 1048576U);
  EXPECT_EQ(c.http.address, "0.0.0.0");
  EXPECT_EQ(c.http.port, 8443);
  ASSERT_EQ(c.http.tokens.size(), 1U);
  EXPECT_EQ(c.http.tokens[0].role, Role::Operator);
  EXPECT_EQ(c.http.tokens[0].sha256, "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08");
}

TEST(Config, EmptyFileGivesDefaults) {
  const Config c = parse_config("", "gw.yaml");
  EXPECT_TRUE(c.networks.empty());
  EXPECT_FALSE(c.mqtt.enabled);
  EXPECT_EQ(c.http.port, 8080);
  EXPECT_EQ(c.http.address, "127.0.0.1");
  EXPECT_TRUE(c.http.auth);
  MqttConfig m;
  EXPECT_EQ(m.qos_for(EventKind::Emcy), 1);   // nothing lost when the broker goes away
  EXPECT_EQ(m.qos_for(EventKind::State), 1);
  EXPECT_EQ(m.qos_for(EventKind::Tpdo), 0);   // high rate, the next value replaces it
}

// Issue 12: where each kind's MQTT messages wait. By default the QoS 0
// kinds stay in memory while the broker is connected (outage) and the QoS 1
// ones go to disk; `default` sets every kind wherever it stands in the map.
TEST(Config, StorageModesPerKindFollowQosByDefault) {
  MqttConfig m;
  EXPECT_EQ(m.storage_for(EventKind::Tpdo), StorageMode::Outage);
  EXPECT_EQ(m.storage_for(EventKind::Heartbeat), StorageMode::Outage);
  EXPECT_EQ(m.storage_for(EventKind::Emcy), StorageMode::Disk);
  EXPECT_EQ(m.storage_for(EventKind::State), StorageMode::Disk);
  m.qos[EventKind::Tpdo] = 1;
  EXPECT_EQ(m.storage_for(EventKind::Tpdo), StorageMode::Disk);

  const Config c = parse_config(R"(
mqtt:
  uri: tcp://x
  qos: {heartbeat: 1}
  queue:
    memory-max-bytes: 1048576
    memory-max-messages: 5000
    storage: {heartbeat: memory, default: outage, emcy: disk}
)", "gw.yaml");
  EXPECT_EQ(c.mqtt.storage_for(EventKind::Heartbeat), StorageMode::Memory);
  EXPECT_EQ(c.mqtt.storage_for(EventKind::Emcy), StorageMode::Disk);
  EXPECT_EQ(c.mqtt.storage_for(EventKind::State), StorageMode::Outage);  // default, though QoS 1
  EXPECT_EQ(c.mqtt.memory_max_bytes, 1048576U);
  EXPECT_EQ(c.mqtt.memory_max_messages, 5000U);
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://x\n  queue: {storage: {tpdo: ram}}\n"),
              HasSubstr("gw.yaml:3: mqtt.queue.storage.tpdo: 'ram' is not disk, outage or memory"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://x\n  queue: {storage: {pdos: disk}}\n"),
              HasSubstr("mqtt.queue.storage.pdos: unknown event kind"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://x\n  queue: {storage: disk}\n"),
              HasSubstr("mqtt.queue.storage: expected kind: mode pairs"));
}

TEST(Config, ErrorsNameFileLineKeyAndReason) {
  EXPECT_EQ(config_error("networks:\n  - interface: can0\n    nodes:\n      - id: 200\n"),
            "gw.yaml:4: networks[0].nodes[0].id: 200 is out of range 1..127");
  EXPECT_EQ(config_error("networks:\n  - interface: can0\n    bitrat: 5\n"),
            "gw.yaml:3: networks[0].bitrat: unknown key (known here: interface, simulated, simulation, bitrate, node-id, "
            "heartbeat-ms, "
            "sync, time, boot, nodes, lss, capture)");
  EXPECT_THAT(config_error("networks:\n  - bitrate: 500000\n"), HasSubstr("networks[0]: missing key 'interface'"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    nodes:\n      - id: 5\n        eds: /nope.eds\n"),
              HasSubstr("gw.yaml:5: networks[0].nodes[0].eds: file '/nope.eds' not found"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://x\n  format: xml\n"), HasSubstr("gw.yaml:3: mqtt.format: 'xml' is not"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://x\n  qos: {tpdo: 3}\n"), HasSubstr("mqtt.qos.tpdo: 3 is out of range 0..2"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://x\n  qos: {pdos: 1}\n"), HasSubstr("mqtt.qos.pdos: unknown event kind"));
  EXPECT_THAT(config_error("mqtt:\n  client-id: x\n"), HasSubstr("mqtt: missing key 'uri'"));
  EXPECT_THAT(config_error("gateway:\n  id: a/b\n"), HasSubstr("gateway.id: 'a/b' cannot be an MQTT topic level"));
  EXPECT_THAT(config_error("gateway:\n  log-level: loud\n"), HasSubstr("gateway.log-level: 'loud' is not one of"));
  EXPECT_THAT(config_error("http:\n  listen: 8080\n"), HasSubstr("http.listen: '8080' is not ADDR:PORT"));
  EXPECT_THAT(config_error("http:\n  tokens:\n    - {name: a, role: root, sha256: x}\n"),
              HasSubstr("http.tokens[0].role: 'root' is not viewer, operator or admin"));
  EXPECT_THAT(config_error("http:\n  tokens:\n    - {name: a, role: admin, sha256: secret}\n"),
              HasSubstr("not a hex SHA-256"));
  EXPECT_THAT(config_error("networks: [1, 2\n"), HasSubstr("gw.yaml:2: not valid YAML"));
  EXPECT_THAT(config_error("networks: can0\n"), HasSubstr("networks: expected a list"));
  EXPECT_EQ(config_error("sync: 1\n"), "gw.yaml:1: sync: unknown key (known here: gateway, networks, mqtt, http, sparkplug, ascii, history)");
  EXPECT_THAT(config_error("- a\n"), HasSubstr("(top level): expected a mapping of keys"));
}

// Contract "Sparkplug B": every sparkplug key reaches its field, and each
// node's sparkplug-metrics objects (YAML plain or quoted, index in hex as in
// the API, an optional sub-index).
TEST(Config, SparkplugKeysReachTheirFields) {
  const std::string dir = ::testing::TempDir();
  const std::string pw = dir + "/spb-password";
  std::ofstream(pw) << "s3cret\n";
  const std::string yaml = "gateway: {id: gw7}\n"
                           "networks:\n  - interface: can0\n    nodes:\n"
                           "      - id: 5\n        sparkplug-metrics: [2300h, \"1017h\", \"6060h:0\", 0x2001, \"2002h:0x1F\"]\n"
                           "sparkplug:\n"
                           "  group-id: plant1\n"
                           "  edge-node-id: line-3\n"
                           "  primary-host-id: scada-1\n"
                           "  aliases: true\n"
                           "  commands-role: admin\n"
                           "  uri: ssl://spb-broker:8883\n"
                           "  client-id: spb-client\n"
                           "  username: edge\n"
                           "  password-file: " + pw + "\n"
                           "  tls: {ca: " + kEds + "}\n"
                           "  mqtt-version: 3.1.1\n"
                           "  keepalive-s: 15\n";
  const Config c = merge(parse_config(yaml, "gw.yaml"), CliOptions{});
  const auto& sp = c.sparkplug;
  EXPECT_TRUE(sp.enabled);
  EXPECT_EQ(sp.origin, "gw.yaml:8: sparkplug.group-id");
  EXPECT_EQ(sp.group_id, "plant1");
  EXPECT_EQ(sp.edge_node_id, "line-3");
  EXPECT_EQ(sp.primary_host_id, "scada-1");
  EXPECT_TRUE(sp.aliases);
  EXPECT_EQ(sp.commands_role, Role::Admin);
  EXPECT_EQ(sp.mqtt.server_uri, "ssl://spb-broker:8883");
  EXPECT_EQ(sp.uri_origin, "gw.yaml:13: sparkplug.uri");
  EXPECT_EQ(sp.mqtt.client_id, "spb-client");
  EXPECT_EQ(sp.mqtt.username, "edge");
  EXPECT_EQ(sp.mqtt.password, "s3cret");
  EXPECT_EQ(sp.mqtt.ca_file, kEds);
  EXPECT_EQ(sp.mqtt.mqtt_version, 4);
  EXPECT_EQ(sp.mqtt.keepalive, 15s);
  EXPECT_EQ(c.networks[0].nodes[0].sparkplug_metrics,
            (std::vector<SparkplugObject>{{0x2300, std::nullopt}, {0x1017, std::nullopt}, {0x6060, 0}, {0x2001, std::nullopt},
                                          {0x2002, 0x1F}}));
  EXPECT_TRUE(parse_config("", "gw.yaml").networks.empty());
  EXPECT_FALSE(parse_config("", "gw.yaml").sparkplug.enabled) << "off unless configured";
}

// Contract "LSS master" (item 3 of issue 16): lss.assign per network gives
// known devices (their LSS address, CiA 305 = 1018h sub 1..4) their node-ID
// at start-up; store defaults to true. Mistakes are one line with the key.
TEST(Config, LssAssignPerNetwork) {
  const std::string yaml = "networks:\n  - interface: can0\n    lss:\n      assign:\n"
                           "        - identity: {vendor-id: 0x12345678, product-code: 2, revision: 3, serial: 0xFFFFFFFF}\n"
                           "          node-id: 42\n"
                           "        - identity: {vendor-id: 1, product-code: 2, revision: 3, serial: 4}\n"
                           "          node-id: 43\n          store: false\n";
  const Config c = parse_config(yaml, "gw.yaml");
  ASSERT_EQ(c.networks[0].lss_assign.size(), 2u);
  const auto& a = c.networks[0].lss_assign[0];
  EXPECT_EQ(a.identity.vendor_id, 0x12345678u);
  EXPECT_EQ(a.identity.product_code, 2u);
  EXPECT_EQ(a.identity.revision, 3u);
  EXPECT_EQ(a.identity.serial, 0xFFFFFFFFu);
  EXPECT_EQ(a.node_id, 42);
  EXPECT_TRUE(a.store) << "stored unless told otherwise";
  EXPECT_FALSE(c.networks[0].lss_assign[1].store);
  EXPECT_TRUE(parse_config("networks:\n  - interface: can0\n", "gw.yaml").networks[0].lss_assign.empty());

  const std::string net = "networks:\n  - interface: can0\n    lss:\n      assign:\n";
  EXPECT_THAT(config_error(net + "        - identity: {vendor-id: 1, product-code: 2, revision: 3}\n          node-id: 5\n"),
              HasSubstr("networks[0].lss.assign[0].identity: missing key 'serial'"));
  EXPECT_THAT(config_error(net + "        - identity: {vendor-id: 1, product-code: 2, revision: 3, serial: 4}\n"
                                 "          node-id: 128\n"),
              HasSubstr("gw.yaml:6: networks[0].lss.assign[0].node-id: 128 is out of range 1..127"));
  EXPECT_THAT(config_error(net + "        - identity: {vendor-id: 1, product-code: 2, revision: 3, serial: 4}\n"
                                 "          node-id: 127\n"),
              HasSubstr("node-id: node 127 is the gateway's own node-ID"));
  EXPECT_THAT(config_error(net + "        - identity: {vendor-id: 1, product-code: 2, revision: 3, serial: 4}\n"
                                 "          node-id: 5\n"
                                 "        - identity: {vendor-id: 9, product-code: 2, revision: 3, serial: 4}\n"
                                 "          node-id: 5\n"),
              HasSubstr("node-ID 5 is assigned twice"));
  EXPECT_THAT(config_error(net + "        - identity: {vendor-id: 1, product-code: 2, revision: 3, serial: 4}\n"
                                 "          node-id: 5\n"
                                 "        - identity: {vendor-id: 1, product-code: 2, revision: 3, serial: 4}\n"
                                 "          node-id: 6\n"),
              HasSubstr("this LSS address is listed twice"));
  EXPECT_THAT(config_error(net + "        - identity: {vendor-id: 1, product-code: 2, revision: 3, serial: 4}\n"
                                 "          node-id: 5\n          stored: true\n"),
              HasSubstr("lss.assign[0].stored: unknown key"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    lss: {scan: true}\n"),
              HasSubstr("networks[0].lss.scan: unknown key (known here: assign)"));
}

// merge(): the edge node id is the gateway id, the broker mqtt's (with its
// credentials and TLS files), the client id canopen-gateway-<id>-spb,
// commands act as operator; --sparkplug turns it on.
TEST(Config, SparkplugDefaultsFromTheGatewayAndMqtt) {
  const Config file = parse_config("gateway: {id: gw7}\nnetworks:\n  - interface: can0\n"
                                   "mqtt: {uri: tcp://broker:1883, username: u, password: p}\n",
                                   "gw.yaml");
  CliOptions cli;
  cli.sparkplug_group = "plant1";
  const Config c = merge(file, cli);
  const auto& sp = c.sparkplug;
  EXPECT_TRUE(sp.enabled);
  EXPECT_EQ(sp.origin, "--sparkplug plant1");
  EXPECT_EQ(sp.group_id, "plant1");
  EXPECT_EQ(sp.edge_node_id, "gw7");
  EXPECT_EQ(sp.primary_host_id, "");
  EXPECT_FALSE(sp.aliases);
  EXPECT_EQ(sp.commands_role, Role::Operator);
  EXPECT_EQ(sp.mqtt.server_uri, "tcp://broker:1883");
  EXPECT_THAT(sp.uri_origin, HasSubstr("gw.yaml:4: mqtt.uri"));
  EXPECT_EQ(sp.mqtt.client_id, "canopen-gateway-gw7-spb");
  EXPECT_EQ(sp.mqtt.username, "u");
  EXPECT_EQ(sp.mqtt.password, "p");
  EXPECT_EQ(sp.mqtt.mqtt_version, 5);
  EXPECT_EQ(sp.mqtt.keepalive, c.mqtt.keepalive);
  EXPECT_FALSE(merge(file, CliOptions{}).sparkplug.enabled);

  // Another broker (sparkplug.uri) gets none of mqtt's credentials.
  const Config other = merge(parse_config("gateway: {id: gw7}\nnetworks:\n  - interface: can0\n"
                                          "mqtt: {uri: tcp://broker:1883, username: u, password: p}\n"
                                          "sparkplug: {group-id: g, uri: tcp://other:1883}\n",
                                          "gw.yaml"),
                             CliOptions{});
  EXPECT_EQ(other.sparkplug.mqtt.server_uri, "tcp://other:1883");
  EXPECT_EQ(other.sparkplug.mqtt.username, "");
  EXPECT_EQ(other.sparkplug.mqtt.password, "");
  // Without MQTT, sparkplug.uri alone is enough.
  const Config alone = merge(parse_config("networks:\n  - interface: can0\nsparkplug: {group-id: g, uri: tcp://b}\n",
                                          "gw.yaml"),
                             CliOptions{});
  EXPECT_FALSE(alone.mqtt.enabled);
  EXPECT_EQ(alone.sparkplug.mqtt.server_uri, "tcp://b");
}

// Every sparkplug mistake is one line naming file, line, key and reason.
TEST(Config, SparkplugErrorsNameFileLineKeyAndReason) {
  const std::string net = "networks:\n  - interface: can0\n";
  EXPECT_EQ(config_error(net + "sparkplug: {edge-node-id: e}\n"),
            "gw.yaml:3: sparkplug: missing key 'group-id' (the Sparkplug group, e.g. plant1)");
  for (const char* bad : {"a/b", "a+b", "'#'", "''", "'with space'"}) {
    EXPECT_THAT(config_error(net + "sparkplug: {group-id: " + bad + "}\n"),
                HasSubstr("gw.yaml:3: sparkplug.group-id: '"))
        << bad;
    EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, edge-node-id: " + bad + "}\n"),
                HasSubstr("sparkplug.edge-node-id: '"))
        << bad;
    EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, primary-host-id: " + bad + "}\n"),
                HasSubstr("sparkplug.primary-host-id: '"))
        << bad;
  }
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: a/b}\n"), HasSubstr("cannot be a Sparkplug id"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, commands-role: root}\n"),
              HasSubstr("sparkplug.commands-role: 'root' is not viewer, operator or admin or none"));
  EXPECT_EQ(parse_config(net + "sparkplug: {group-id: g, commands-role: none}\n", "gw.yaml").sparkplug.commands_role,
            Role::None);
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, aliases: maybe}\n"),
              HasSubstr("sparkplug.aliases: 'maybe' is not true or false"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, mqtt-version: 3}\n"),
              HasSubstr("sparkplug.mqtt-version: '3' is not 5"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, keepalive-s: 0}\n"),
              HasSubstr("sparkplug.keepalive-s: 0 is out of range 1..65535"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, tls: {cert: " + kEds + "}}\n"),
              HasSubstr("sparkplug.tls: cert and key go together"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, tls: {ca: /nope.pem}}\n"),
              HasSubstr("sparkplug.tls.ca: file '/nope.pem' not found"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, password: a, password-file: /nope}\n"),
              HasSubstr("give either password or password-file"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, password-file: /nope}\n"),
              HasSubstr("sparkplug.password-file: cannot read '/nope'"));
  EXPECT_THAT(config_error(net + "sparkplug: {group-id: g, qos: 1}\n"),
              HasSubstr("gw.yaml:3: sparkplug.qos: unknown key (known here: group-id,"));
  const std::string node = "networks:\n  - interface: can0\n    nodes:\n      - id: 5\n        sparkplug-metrics: ";
  EXPECT_EQ(config_error(node + "[2300h, 12345h]\n"),
            "gw.yaml:5: networks[0].nodes[0].sparkplug-metrics[1]: '12345h' is not an object (e.g. 2300h, 6060h:0)");
  EXPECT_THAT(config_error(node + "[\"6060h:256\"]\n"), HasSubstr("'6060h:256' is not an object"));
  EXPECT_THAT(config_error(node + "[\"6060h:\"]\n"), HasSubstr("'6060h:' is not an object"));
  EXPECT_THAT(config_error(node + "[speed]\n"), HasSubstr("'speed' is not an object"));
  EXPECT_THAT(config_error(node + "[2300h, \"2300h\"]\n"), HasSubstr("sparkplug-metrics[1]: '2300h' is listed twice"));
  EXPECT_THAT(config_error(node + "2300h\n"), HasSubstr("sparkplug-metrics: expected a list"));

  // merge(): no broker at all, and a client id the native session has.
  EXPECT_EQ(merge_error(parse_config(net + "sparkplug: {group-id: g}\n", "gw.yaml"), CliOptions{}),
            "gw.yaml:3: sparkplug.group-id: no broker for the Sparkplug edge node: set sparkplug.uri, or turn MQTT on "
            "(mqtt.uri or --mqtt; Sparkplug then uses the same broker)");
  CliOptions flag;
  flag.sparkplug_group = "g";
  EXPECT_THAT(merge_error(parse_config(net, "gw.yaml"), flag), HasSubstr("--sparkplug g: no broker"));
  EXPECT_THAT(merge_error(parse_config(net + "mqtt: {uri: tcp://b, client-id: same}\n"
                                             "sparkplug: {group-id: g, client-id: same}\n",
                                       "gw.yaml"),
                          CliOptions{}),
              HasSubstr("sparkplug.client-id 'same' is mqtt's as well"));
}

TEST(Config, NodeRulesAreChecked) {
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    nodes:\n      - {id: 5}\n      - {id: 5}\n"),
              HasSubstr("networks[0].nodes[1]: node 5 is listed twice"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    nodes:\n      - {id: 127}\n"),
              HasSubstr("node 127 is the gateway's own node-ID"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    nodes:\n      - {id: 5, boot: {configure: true}}\n"),
              HasSubstr("configure: true needs an eds or dcf file"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    nodes:\n      - {id: 5, guarding: {guard-time-ms: 100}}\n"),
              HasSubstr("must both be set"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n  - interface: can0\n"),
              HasSubstr("networks[1]: interface can0 is configured twice"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    sync: {counter-overflow: 1}\n"),
              HasSubstr("1 is reserved"));
}

// api-contract "Node monitoring without configuration": auto (the default)
// watches the node anyway, 0 turns watching off, a number is the consumer
// time (1016h).
TEST(Config, HeartbeatConsumerIsAutoByDefaultZeroOrATime) {
  const Config c = parse_config(
      "networks:\n  - interface: can0\n    nodes:\n"
      "      - {id: 1}\n"
      "      - {id: 2, heartbeat-consumer-ms: auto}\n"
      "      - {id: 3, heartbeat-consumer-ms: 0}\n"
      "      - {id: 4, heartbeat-consumer-ms: 1500}\n"
      "      - {id: 5, heartbeat-consumer-ms: 0x3E8}\n",
      "gw.yaml");
  const auto& nodes = c.networks.at(0).nodes;
  ASSERT_EQ(nodes.size(), 5U);
  EXPECT_EQ(nodes[0].heartbeat_consumer, std::nullopt) << "absent: auto";
  EXPECT_EQ(nodes[1].heartbeat_consumer, std::nullopt);
  EXPECT_EQ(nodes[2].heartbeat_consumer, 0ms) << "0: not watched";
  EXPECT_EQ(nodes[3].heartbeat_consumer, 1500ms);
  EXPECT_EQ(nodes[4].heartbeat_consumer, 1000ms);
  // A node given on the command line only is watched automatically too.
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  cli.eds = {{5, kEds}};
  EXPECT_EQ(merge(Config{}, cli).networks.at(0).nodes.at(0).heartbeat_consumer, std::nullopt);

  const std::string node = "networks:\n  - interface: can0\n    nodes:\n      - id: 5\n        heartbeat-consumer-ms: ";
  EXPECT_EQ(config_error(node + "never\n"),
            "gw.yaml:5: networks[0].nodes[0].heartbeat-consumer-ms: 'never' is not auto, 0 (not watched) or a consumer "
            "time in ms (1..65535)");
  EXPECT_EQ(config_error(node + "-5\n"),
            "gw.yaml:5: networks[0].nodes[0].heartbeat-consumer-ms: '-5' is not auto, 0 (not watched) or a consumer "
            "time in ms (1..65535)");
  EXPECT_EQ(config_error(node + "70000\n"),
            "gw.yaml:5: networks[0].nodes[0].heartbeat-consumer-ms: 70000 is out of range 0..65535");
  EXPECT_EQ(config_error(node + "1.5\n"),
            "gw.yaml:5: networks[0].nodes[0].heartbeat-consumer-ms: '1.5' is not a whole number");
  EXPECT_THAT(config_error(node + "[1]\n"), HasSubstr("heartbeat-consumer-ms: expected a single value"));
}

// Issue 17 item 1: one `nodes:` entry on its own (PUT .../config, the
// state-dir overlay) is read by the file's rules with the file's reasons;
// node_config_json() writes what parse_node_config() reads back the same.
TEST(Config, OneNodeEntryAloneHasTheFilesRulesAndReasons) {
  const std::string dir = std::string(CANOPEN_SOURCE_DIR) + "/deploy/eds";
  const NodeConfig n = parse_node_config(
      R"({"id": 5, "name": "drive", "eds": "cia402-drive.eds", "heartbeat-consumer-ms": 1500,
          "guarding": {"guard-time-ms": 100, "life-time-factor": 3},
          "boot": {"configure": true, "start": true, "read-pdo-config": false}, "sparkplug-metrics": ["2300h", "6060h:0"]})",
      "request body", dir, false);
  EXPECT_EQ(n.id, 5);
  EXPECT_EQ(n.name, "drive");
  EXPECT_EQ(n.eds, kEds) << "relative to the directory given";
  EXPECT_EQ(n.heartbeat_consumer, 1500ms);
  EXPECT_EQ(n.guarding.guard_time, 100ms);
  ASSERT_TRUE(n.boot);
  EXPECT_TRUE(n.boot->configure);
  EXPECT_EQ(n.boot->read_pdo_config, false);
  ASSERT_EQ(n.sparkplug_metrics.size(), 2U);

  // Round trip through the JSON keys (JSON is YAML).
  const NodeConfig back = parse_node_config(boost::json::serialize(node_config_json(n)), "x", "", false);
  EXPECT_EQ(node_config_json(back), node_config_json(n));
  EXPECT_EQ(back.sparkplug_metrics, n.sparkplug_metrics);
  EXPECT_EQ(back.guarding.life_time_factor, 3);

  // The same reason as in a file, without a line number for a body.
  const std::string file_reason =
      config_error("networks:\n  - interface: can0\n    nodes:\n      - {id: 5, heartbeat-consumer-ms: never}\n");
  std::string body_reason;
  try {
    (void)parse_node_config(R"({"id": 5, "heartbeat-consumer-ms": "never"})", "request body", "", false);
  } catch (const ConfigError& e) {
    body_reason = e.what();
  }
  EXPECT_EQ(body_reason,
            "request body: heartbeat-consumer-ms: 'never' is not auto, 0 (not watched) or a consumer time in ms "
            "(1..65535)");
  EXPECT_THAT(file_reason, HasSubstr("heartbeat-consumer-ms: 'never' is not auto, 0 (not watched)"));
  EXPECT_THROW((void)parse_node_config(R"({"id": 5, "colour": "red"})", "b", "", false), ConfigError);
  EXPECT_THROW((void)parse_node_config("[1, 2]", "b", "", false), ConfigError);
  EXPECT_THROW((void)parse_node_config(R"({"id": 5, "eds": "missing.eds"})", "b", dir, false), ConfigError);
  // In a file the line is named.
  try {
    (void)parse_node_config("id: 5\nguarding: {guard-time-ms: 100}\n", "net1-node5.yaml", "");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("net1-node5.yaml:2: guarding: guard-time-ms and life-time-factor"));
  }
}

// Issue 11: boot: {read-pdo-config: true} per network (default for its
// nodes, simulated ones included) and per node (wins).
TEST(Config, ReadPdoConfigPerNetworkAndPerNode) {
  const Config c = parse_config("networks:\n  - interface: can0\n    boot: {read-pdo-config: true}\n    nodes:\n"
                                "      - {id: 5, eds: " + kEds + ", boot: {start: true}}\n"
                                "      - {id: 6, eds: " + kEds + ", boot: {read-pdo-config: false}}\n"
                                "  - simulated: true\n    boot: {read-pdo-config: true}\n"
                                "  - interface: can1\n    nodes:\n      - {id: 7, eds: " + kIo +
                                ", boot: {read-pdo-config: true}}\n",
                                "gw.yaml");
  ASSERT_EQ(c.networks.size(), 3U);
  EXPECT_TRUE(c.networks[0].read_pdo_config);
  EXPECT_FALSE(c.networks[0].nodes[0].boot->read_pdo_config.has_value()) << "the network's applies";
  EXPECT_EQ(c.networks[0].nodes[1].boot->read_pdo_config, false);
  EXPECT_TRUE(c.networks[1].read_pdo_config);
  EXPECT_FALSE(c.networks[2].read_pdo_config);
  EXPECT_EQ(c.networks[2].nodes[0].boot->read_pdo_config, true);
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    nodes:\n      - {id: 5, boot: {read-pdo-config: true}}\n"),
              HasSubstr("read-pdo-config: true needs an eds or dcf file"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    boot: {start: true}\n"),
              HasSubstr("networks[0].boot.start: unknown key"));
}

// Issue 28 item 1 (CiA 302-2): at its start the manager boots nodes as it
// finds them (default) or resets their communication first.
TEST(Config, BootAtStartIsAsFoundUnlessResetCommunicationIsAsked) {
  const Config c = parse_config("networks:\n  - interface: can0\n  - interface: can1\n    boot: {at-start: as-found}\n"
                                "  - interface: can2\n    boot: {at-start: reset-communication}\n",
                                "gw.yaml");
  ASSERT_EQ(c.networks.size(), 3U);
  EXPECT_EQ(c.networks[0].boot_at_start, NetworkConfig::BootAtStart::AsFound);
  EXPECT_EQ(c.networks[1].boot_at_start, NetworkConfig::BootAtStart::AsFound);
  EXPECT_EQ(c.networks[2].boot_at_start, NetworkConfig::BootAtStart::ResetCommunication);
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    boot: {at-start: reset-node}\n"),
              HasSubstr("'reset-node' is not as-found or reset-communication"));
}

TEST(Config, FlagsWinOverTheFile) {
  Config file = parse_config("gateway: {id: from-file, node-id: 100, log-level: warn}\n"
                             "networks:\n  - interface: can0\n    heartbeat-ms: 250\n  - interface: can1\n"
                             "mqtt: {uri: tcp://file:1883}\nhttp: {listen: 127.0.0.1:9000}\n",
                             "gw.yaml");
  CliOptions cli;
  cli.gateway_id = "from-flag";
  cli.node_id = 42;
  cli.log_level = LogLevel::Trace;
  cli.mqtt_uri = "tcp://flag:1883";
  cli.mqtt_format = "protobuf";
  cli.http = "127.0.0.1:9999";
  cli.can_interfaces = {"can1", "vcan9"};
  const Config c = merge(file, cli);
  EXPECT_EQ(c.gateway_id, "from-flag");
  EXPECT_EQ(c.log_level, LogLevel::Trace);
  EXPECT_EQ(c.mqtt.server_uri, "tcp://flag:1883");
  EXPECT_EQ(c.mqtt.format, PayloadFormat::Protobuf);
  EXPECT_EQ(c.http.port, 9999);
  ASSERT_EQ(c.networks.size(), 2U);  // --can replaces the file's list, in flag order
  EXPECT_EQ(c.networks[0].interface, "can1");
  EXPECT_EQ(c.networks[1].interface, "vcan9");
  EXPECT_EQ(c.networks[0].node_id, 42);
  EXPECT_EQ(c.networks[1].node_id, 42);

  // Without flags, the file's values stay.
  const Config d = merge(file, CliOptions{});
  EXPECT_EQ(d.gateway_id, "from-file");
  EXPECT_EQ(d.networks.size(), 2U);
  EXPECT_EQ(d.networks[0].heartbeat_producer, 250ms);
  EXPECT_EQ(d.mqtt.client_id, "canopen-gateway-from-file");
}

TEST(Config, EdsFlagDescribesTheNodeOnEveryNetwork) {
  CliOptions cli;
  cli.can_interfaces = {"can0", "can1"};
  cli.eds = {{5, kEds}};
  const Config c = merge(Config{}, cli);
  for (const auto& net : c.networks) {
    ASSERT_EQ(net.nodes.size(), 1U);
    EXPECT_EQ(net.nodes[0].id, 5);
    EXPECT_EQ(net.nodes[0].eds, kEds);
  }
  cli.eds = {{5, "/missing.eds"}};
  EXPECT_THAT(merge_error(Config{}, cli), HasSubstr("--eds 5=/missing.eds: file not found"));
}

// --demo --eds N=FILE: no real network takes the file, yet it is read with
// the same rules as every other path (and `canopen-eds check`).
TEST(Config, EdsFlagFileIsReadEvenWithDemoAlone) {
  const auto dir = std::filesystem::temp_directory_path() / ("cfg-eds-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto bad = (dir / "bad.eds").string();
  std::ofstream(bad) << "[1000]\nParameterName=Device type\nDataType=0x0007\nAccessType=ro\nAccessType=rw\n";
  CliOptions cli;
  cli.demo = true;
  cli.eds = {{5, bad}};
  EXPECT_THAT(merge_error(Config{}, cli), HasSubstr("--eds 5=" + bad + ": " + bad + ":5: key 'AccessType' in [1000] repeated"));
  cli.eds = {{5, kEds}};
  EXPECT_NO_THROW(merge(Config{}, cli));
  std::filesystem::remove_all(dir);
}

TEST(Config, DemoAddsASimulatedNetworkWithoutAuthOnLoopback) {
  CliOptions cli;
  cli.demo = true;
  const Config c = merge(Config{}, cli);
  ASSERT_EQ(c.networks.size(), 1U);
  EXPECT_TRUE(c.networks[0].simulated);
  EXPECT_EQ(c.networks[0].sync.period, 100ms) << "SYNC for the drive's synchronous TPDOs";
  EXPECT_EQ(c.networks[0].bitrate, 250000U) << "a bus load to show (issue 18)";
  EXPECT_TRUE(c.demo);
  EXPECT_TRUE(c.http.loopback());
  EXPECT_FALSE(c.http.auth);
  EXPECT_FALSE(c.mqtt.enabled);  // MQTT only when asked for
  EXPECT_FALSE(c.gateway_id.empty());
}

// api-contract "Command line": --demo turns authentication off only on
// loopback without tokens (issue 12 item 11).
TEST(Config, DemoWithTokensRequiresThem) {
  CliOptions cli;
  cli.demo = true;
  const Config c = merge(parse_config("http:\n  tokens:\n    - {name: a, role: viewer, sha256: "
                                      "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08}\n",
                                      "gw.yaml"),
                         cli);
  EXPECT_TRUE(c.http.auth);
  EXPECT_EQ(c.http.anonymous_role(), Role::None) << "a caller without a token gets nothing";
}

TEST(Config, DemoOffLoopbackWithoutTokensIsRefused) {
  CliOptions cli;
  cli.demo = true;
  cli.http = "0.0.0.0:8080";
  const auto error = merge_error(Config{}, cli);
  EXPECT_THAT(error, HasSubstr("--http 0.0.0.0:8080: not a loopback address, and no http.tokens are configured"));
  EXPECT_THAT(error, HasSubstr("--demo turns authentication off on loopback only"));
  EXPECT_EQ(error.find('\n'), std::string::npos) << "one line";
  // From the file too; with tokens the normal rules go on (TLS or plain-http).
  CliOptions demo_only;
  demo_only.demo = true;
  EXPECT_THAT(merge_error(parse_config("http: {listen: \"[::]:8080\"}\n", "gw.yaml"), demo_only),
              HasSubstr("gw.yaml:1: http.listen [::]:8080: not a loopback address, and no http.tokens are configured "
                        "in gw.yaml"));
  // Explicitly without authentication, as without --demo: allowed (not advised).
  EXPECT_FALSE(merge(parse_config("http: {auth: false}\n", "gw.yaml"), cli).http.auth);
}

TEST(Config, SimulatedNetworksInTheFile) {
  const Config c = parse_config("networks:\n  - simulated: true\n    simulation: {tpdo-period-ms: 5, heartbeat-ms: 100}\n"
                                "  - interface: can0\n",
                                "gw.yaml");
  ASSERT_EQ(c.networks.size(), 2U);
  EXPECT_TRUE(c.networks[0].simulated);
  EXPECT_EQ(c.networks[0].simulation.tpdo_period, 5ms);
  EXPECT_EQ(c.networks[0].simulation.heartbeat, 100ms);
  EXPECT_EQ(c.networks[0].simulation.emcy_period, 20000ms);
  EXPECT_FALSE(c.networks[1].simulated);
  EXPECT_THAT(config_error("networks:\n  - {simulated: true, interface: can0}\n"), HasSubstr("has no interface"));
  EXPECT_THAT(config_error("networks:\n  - {simulated: true, nodes: [{id: 3}]}\n"), HasSubstr("built-in devices"));
  EXPECT_THAT(config_error("networks:\n  - {interface: can0, simulation: {heartbeat-ms: 1}}\n"),
              HasSubstr("only for a network with simulated: true"));
}

TEST(Config, NothingToRunIsAnError) {
  EXPECT_THAT(merge_error(parse_config("mqtt: {uri: tcp://x:1}\n", "gw.yaml"), CliOptions{}),
              HasSubstr("gw.yaml: networks: no network configured"));
}

TEST(Config, AnOpenListenerNeedsTokensAndTls) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  cli.http = "0.0.0.0:8080";
  EXPECT_THAT(merge_error(Config{}, cli), HasSubstr("--http 0.0.0.0:8080: not a loopback address, and no http.tokens"));
  const std::string tokens =
      "http:\n  tokens:\n    - {name: a, role: admin, sha256: "
      "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08}\n";
  // Tokens over plain HTTP off loopback: only when asked for.
  EXPECT_THAT(merge_error(parse_config(tokens, "gw.yaml"), cli),
              HasSubstr("--http 0.0.0.0:8080: not a loopback address, and bearer tokens would cross the network in "
                        "clear text; configure http.tls (cert, key) in gw.yaml"));
  EXPECT_NO_THROW(merge(parse_config(tokens + "  plain-http: true\n", "gw.yaml"), cli));
  Config open = parse_config("http: {auth: false}\n", "gw.yaml");
  EXPECT_NO_THROW(merge(open, cli));
}

// Issue 13: an error about a merged value blames where that value came from
// (the flag, the file's line, or the default), not a key it did not come
// from: `--http 0.0.0.0` with a file that has no tokens is the flag's doing.
TEST(Config, ListenErrorsBlameWhereTheAddressCameFrom) {
  const Config file = parse_config("gateway: {id: gw}\nhttp:\n  auth: true\n", "gw.yaml");
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  cli.http = "0.0.0.0:8080";
  const auto from_flag = merge_error(file, cli);
  EXPECT_EQ(from_flag.rfind("--http 0.0.0.0:8080: ", 0), 0U) << from_flag;
  EXPECT_THAT(from_flag, Not(ContainsRegex("gw\\.yaml:[0-9]"))) << "no line of the file is to blame";
  EXPECT_THAT(from_flag, Not(HasSubstr("http.tokens:"))) << "nor the http.tokens key";

  CliOptions can_only;
  can_only.can_interfaces = {"can0"};
  const auto from_file = merge_error(parse_config("gateway: {id: gw}\nhttp:\n  listen: 0.0.0.0:8080\n", "gw.yaml"),
                                     can_only);
  EXPECT_EQ(from_file.rfind("gw.yaml:3: http.listen 0.0.0.0:8080: ", 0), 0U) << from_file;

  // What merge() records for messages after it (the listener in main.cpp).
  EXPECT_EQ(merge(Config{}, can_only).http.listen_origin, "http.listen not set, default 127.0.0.1:8080");
  EXPECT_EQ(merge(parse_config("http: {listen: 127.0.0.1:9000}\n", "gw.yaml"), can_only).http.listen_origin,
            "gw.yaml:1: http.listen 127.0.0.1:9000");
  CliOptions flag = can_only;
  flag.http = "127.0.0.1:9001";
  EXPECT_EQ(merge(parse_config("http: {listen: 127.0.0.1:9000}\n", "gw.yaml"), flag).http.listen_origin,
            "--http 127.0.0.1:9001");
}

// Contract "CiA 309-3 ASCII interface": `ascii:` keys reach their fields;
// the section alone turns the server on at cocomm's default port.
TEST(Config, AsciiKeysReachTheirFields) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  const Config c = merge(parse_config("ascii:\n  listen: unix:/run/gw/ascii.sock\n  role: viewer\n"
                                      "  idle-timeout-s: 30\n  max-clients: 4\n",
                                      "gw.yaml"),
                         cli);
  EXPECT_TRUE(c.ascii.enabled);
  EXPECT_EQ(c.ascii.listen, "unix:/run/gw/ascii.sock");
  EXPECT_EQ(c.ascii.role, Role::Viewer);
  EXPECT_EQ(c.ascii.idle_timeout, 30s);
  EXPECT_EQ(c.ascii.max_clients, 4U);
  EXPECT_FALSE(merge(Config{}, cli).ascii.enabled) << "off unless asked for";
  const Config defaults = merge(parse_config("ascii: {}\n", "gw.yaml"), cli);
  EXPECT_TRUE(defaults.ascii.enabled);
  EXPECT_EQ(defaults.ascii.listen, "127.0.0.1:60000");
  EXPECT_EQ(defaults.ascii.role, Role::Admin) << "contract: no tokens and a local socket: admin, as REST";
  CliOptions flag = cli;
  flag.ascii = "127.0.0.1:0";
  const Config f = merge(parse_config("ascii: {listen: 127.0.0.1:60001}\n", "gw.yaml"), flag);
  EXPECT_EQ(f.ascii.listen, "127.0.0.1:0") << "the flag wins";
  EXPECT_EQ(f.ascii.listen_origin, "--ascii 127.0.0.1:0");
}

// The socket has no authentication of its own: off loopback/unix only with
// Issue 28 item 6: ascii.role's default follows REST's tokenless rule
// (contract "ASCII"): admin with no tokens on a loopback or unix socket,
// operator once tokens exist or the port is reachable from elsewhere; a
// role given explicitly always wins.
// Issue 28 item 4: the own node's 1000h and 1018h sub 1/4 from the
// gateway: section, on every network; the serial defaults to one per
// machine (its /etc/machine-id).
TEST(Config, TheOwnNodesIdentityKeysReachEveryNetwork) {
  CliOptions cli;
  cli.can_interfaces = {"can0", "can1"};
  const Config c = merge(parse_config("gateway:\n  device-type: 0x00000191\n  vendor-id: 0x4A2\n"
                                      "  serial-number: 1234\n",
                                      "gw.yaml"),
                         cli);
  ASSERT_EQ(c.networks.size(), 2U);
  for (const auto& n : c.networks) {
    EXPECT_EQ(n.identity.device_type, 0x191U);
    EXPECT_EQ(n.identity.vendor_id, 0x4A2U);
    EXPECT_EQ(n.identity.serial, 1234U);
  }
  const Config d = merge(Config{}, cli);
  EXPECT_EQ(d.networks[0].identity.device_type, 309U);
  ASSERT_TRUE(d.networks[0].identity.serial.has_value()) << "always given a serial";
  EXPECT_EQ(d.networks[0].identity.serial, d.networks[1].identity.serial);
  EXPECT_EQ(serial_from_machine_id("3f9a01bc8d2e4f6a9b0c1d2e3f405162\n"), 0x3F9A01BCU);
  EXPECT_EQ(serial_from_machine_id("short"), std::nullopt);
  EXPECT_EQ(serial_from_machine_id("uninitialized"), std::nullopt) << "systemd's placeholder";
  EXPECT_THAT(config_error("gateway:\n  vendor-id: 0x100000000\n"), HasSubstr("vendor-id"));
}

TEST(Config, AsciiRoleDefaultFollowsRestsTokenlessRule) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  const auto role = [&](const std::string& yaml) { return merge(parse_config(yaml, "gw.yaml"), cli).ascii.role; };
  EXPECT_EQ(role("ascii: {listen: unix:/run/gw/ascii.sock}\n"), Role::Admin);
  EXPECT_EQ(role("ascii: {listen: 127.0.0.1:60000}\n"), Role::Admin);
  const std::string tokens =
      "http:\n  tokens:\n    - {name: ops, role: operator, sha256: "
      "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08}\n";
  EXPECT_EQ(role(tokens + "ascii: {}\n"), Role::Operator) << "tokens: the ASCII port has none, so not admin";
  EXPECT_EQ(role("ascii: {listen: 0.0.0.0:60000, allow-remote: true}\n"), Role::Operator) << "reachable remotely";
  EXPECT_EQ(role("ascii: {role: viewer}\n"), Role::Viewer);
  EXPECT_EQ(role(tokens + "ascii: {role: admin}\n"), Role::Admin) << "explicit wins";
}

// ascii.allow-remote: true, refused otherwise with where the address came from.
TEST(Config, AsciiOffLoopbackNeedsAllowRemote) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  cli.ascii = "0.0.0.0:60000";
  EXPECT_THAT(merge_error(Config{}, cli),
              HasSubstr("--ascii 0.0.0.0:60000: not a loopback address or unix socket, and the ASCII interface has no "
                        "authentication of its own; set ascii.allow-remote: true"));
  EXPECT_NO_THROW(merge(parse_config("ascii: {allow-remote: true}\n", "gw.yaml"), cli));
  CliOptions can_only;
  can_only.can_interfaces = {"can0"};
  EXPECT_THAT(merge_error(parse_config("ascii:\n  listen: 10.0.0.1:60000\n", "gw.yaml"), can_only),
              HasSubstr("gw.yaml:2: ascii.listen 10.0.0.1:60000: not a loopback address"));
  cli.ascii = "[::1]:60000";
  EXPECT_NO_THROW(merge(Config{}, cli)) << "IPv6 loopback";
  cli.ascii = "localhost:60000";
  EXPECT_NO_THROW(merge(Config{}, cli));
  cli.ascii = "plc.example:60000";
  EXPECT_THAT(merge_error(Config{}, cli), HasSubstr("is not ADDR:PORT (an IP address) or unix:/path"));
  EXPECT_THAT(config_error("ascii: {listen: 60000}\n"), HasSubstr("gw.yaml:1: ascii.listen: '60000' is not ADDR:PORT"));
  EXPECT_THAT(config_error("ascii: {role: none}\n"), HasSubstr("ascii.role: 'none' is not viewer, operator or admin"));
  EXPECT_THAT(config_error("ascii: {max-clients: 0}\n"), HasSubstr("ascii.max-clients: 0 is out of range 1..1024"));
  EXPECT_THAT(config_error("ascii: {port: 1}\n"), HasSubstr("unknown key"));
}

// The server binds an address and does not resolve names: a name is refused
// at start with its origin; "localhost" is taken as 127.0.0.1.
TEST(Config, ListenAddressIsAnIpAddress) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  cli.http = "localhost:8080";
  const Config c = merge(Config{}, cli);
  EXPECT_EQ(c.http.address, "127.0.0.1");
  EXPECT_TRUE(c.http.loopback());
  cli.http = "[::1]:8080";
  EXPECT_EQ(merge(Config{}, cli).http.address, "::1");
  cli.http = "gw.plant.example:8080";
  EXPECT_THAT(merge_error(Config{}, cli),
              HasSubstr("--http gw.plant.example:8080: 'gw.plant.example' is not an IP address"));
  CliOptions can_only;
  can_only.can_interfaces = {"can0"};
  EXPECT_THAT(merge_error(parse_config("http:\n  listen: gw.plant.example:80\n", "gw.yaml"), can_only),
              HasSubstr("gw.yaml:2: http.listen gw.plant.example:80: 'gw.plant.example' is not an IP address"));
}

TEST(Config, MqttUriOriginIsTheFlagOrTheKey) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  EXPECT_EQ(merge(parse_config("mqtt:\n  uri: tcp://b:1883\n", "gw.yaml"), cli).mqtt.uri_origin, "gw.yaml:2: mqtt.uri");
  cli.mqtt_uri = "tcp://c:1883";
  EXPECT_EQ(merge(parse_config("mqtt:\n  uri: tcp://b:1883\n", "gw.yaml"), cli).mqtt.uri_origin, "--mqtt tcp://c:1883");
}

// Issue 27 item 1 (contract "Brokers"): the native session has
// mqtt.mqtt-version as Sparkplug has sparkplug.mqtt-version.
TEST(Config, MqttVersionIsFiveOr311) {
  EXPECT_EQ(parse_config("mqtt: {uri: tcp://b:1883}\n", "gw.yaml").mqtt.mqtt_version, 5);
  EXPECT_EQ(parse_config("mqtt: {uri: tcp://b:1883, mqtt-version: 3.1.1}\n", "gw.yaml").mqtt.mqtt_version, 4);
  EXPECT_EQ(parse_config("mqtt: {uri: tcp://b:1883, mqtt-version: 5}\n", "gw.yaml").mqtt.mqtt_version, 5);
  EXPECT_THAT(config_error("mqtt: {uri: tcp://b:1883, mqtt-version: 3}\n"), HasSubstr("mqtt.mqtt-version: '3' is not 5"));
}

// Issue 27 item 2 (contract "Brokers"): mqtt.uri and sparkplug.uri take
// one URI or a list, tried in turn; Sparkplug on mqtt's brokers inherits
// the whole list (and, being the same brokers, the credentials); --mqtt
// replaces the list with its one URI.
TEST(Config, BrokerUriListsForClustersAndStandbys) {
  const auto c = parse_config("mqtt: {uri: [tcp://a:1883, ssl://b:8883, mqtt://c]}\n", "gw.yaml");
  EXPECT_EQ(c.mqtt.server_uri, "tcp://a:1883");
  EXPECT_EQ(c.mqtt.standby_uris, (std::vector<std::string>{"ssl://b:8883", "mqtt://c"}));
  EXPECT_EQ(c.mqtt.uris(), (std::vector<std::string>{"tcp://a:1883", "ssl://b:8883", "mqtt://c"}));
  EXPECT_TRUE(parse_config("mqtt: {uri: tcp://a:1883}\n", "gw.yaml").mqtt.standby_uris.empty());
  EXPECT_EQ(parse_config("mqtt:\n  uri:\n    - tcp://a\n    - tcp://b\n", "gw.yaml").mqtt.uris(),
            (std::vector<std::string>{"tcp://a", "tcp://b"}));
  EXPECT_THAT(config_error("mqtt: {uri: []}\n"), HasSubstr("mqtt.uri: no broker URI"));
  EXPECT_THAT(config_error("mqtt: {uri: [tcp://a, tcp://a]}\n"), HasSubstr("'tcp://a' is in the list twice"));

  const std::string base = "gateway: {id: gw7}\nnetworks:\n  - interface: can0\n"
                           "mqtt: {uri: [tcp://a:1883, tcp://b:1883], username: u, password: p}\n";
  const Config inherited = merge(parse_config(base + "sparkplug: {group-id: g}\n", "gw.yaml"), CliOptions{});
  EXPECT_EQ(inherited.sparkplug.mqtt.uris(), (std::vector<std::string>{"tcp://a:1883", "tcp://b:1883"}));
  EXPECT_EQ(inherited.sparkplug.mqtt.username, "u") << "the same brokers: mqtt's credentials";
  const Config listed =
      merge(parse_config(base + "sparkplug: {group-id: g, uri: [tcp://a:1883, tcp://b:1883]}\n", "gw.yaml"),
            CliOptions{});
  EXPECT_EQ(listed.sparkplug.mqtt.username, "u") << "the same list, the same brokers";
  const Config other =
      merge(parse_config(base + "sparkplug: {group-id: g, uri: [tcp://s1:1883, tcp://s2:1883]}\n", "gw.yaml"),
            CliOptions{});
  EXPECT_EQ(other.sparkplug.mqtt.uris(), (std::vector<std::string>{"tcp://s1:1883", "tcp://s2:1883"}));
  EXPECT_EQ(other.sparkplug.mqtt.username, "") << "other brokers get none of mqtt's credentials";

  CliOptions cli;
  cli.mqtt_uri = "tcp://flag:1883";
  EXPECT_EQ(merge(parse_config(base, "gw.yaml"), cli).mqtt.uris(), std::vector<std::string>{"tcp://flag:1883"});
}

// A control character in the file is not echoed raw into the one-line
// error (it could end the line or drive the terminal): it reads \xNN.
TEST(Config, ControlCharactersInMessagesAreEscaped) {
  for (const std::string& yaml : {std::string("gateway:\n  id: ab\x01" "cd\n"),
                                 std::string("gateway:\n  id: \"ab\\x1b[2Jcd\"\n"),
                                 std::string("networks:\n  - interface: \"can\\r0\\x7f\"\n    bitrate: 7\n")}) {
    const auto error = config_error(yaml);
    ASSERT_FALSE(error.empty());
    for (const char ch : error) {
      const auto u = static_cast<unsigned char>(ch);
      EXPECT_TRUE(u >= 0x20 && u != 0x7F) << "raw control character " << static_cast<int>(u) << " in: " << error;
    }
  }
  EXPECT_THAT(config_error("gateway:\n  id: ab\x01" "cd\n"), HasSubstr("gw.yaml:2: gateway.id: 'ab\\x01cd'"));
  EXPECT_THAT(config_error("gateway:\n  id: \"ab\\x1b[2Jcd\"\n"), HasSubstr("'ab\\x1B[2Jcd'"));
}

// The own node-ID clash blames the flag that brought the two together.
TEST(Config, OwnNodeIdClashBlamesTheFlag) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  cli.eds = {{5, kEds}};
  cli.node_id = 5;
  EXPECT_THAT(merge_error(Config{}, cli), HasSubstr("--eds 5=" + kEds + ": node 5 is the gateway's own node-ID on can0"));
  CliOptions node_flag;
  node_flag.node_id = 10;
  EXPECT_THAT(merge_error(parse_config("networks:\n  - interface: can0\n    nodes: [{id: 10}]\n", "gw.yaml"), node_flag),
              HasSubstr("--node-id 10: node 10 is the gateway's own node-ID on can0"));
}

// gateway.node-id is the own node-ID of networks the flags add, too.
TEST(Config, GatewayNodeIdAppliesToNetworksFromFlags) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  cli.demo = true;
  const Config c = merge(parse_config("gateway: {node-id: 100}\n", "gw.yaml"), cli);
  ASSERT_EQ(c.networks.size(), 2U);
  EXPECT_EQ(c.networks[0].node_id, 100);
  EXPECT_EQ(c.networks[1].node_id, 100);
  EXPECT_EQ(merge(Config{}, cli).networks[0].node_id, 127);
}

TEST(Config, BrowserHostsOriginsAndConnectionLimits) {
  const Config c = parse_config(
      "http:\n  host-names: [gw.plant.example, 10.9.8.7]\n  allowed-origins: [https://scada.example, '*']\n"
      "  max-connections: 64\n  max-connections-per-address: 8\n",
      "gw.yaml");
  EXPECT_EQ(c.http.host_names, (std::vector<std::string>{"gw.plant.example", "10.9.8.7"}));
  EXPECT_EQ(c.http.allowed_origins, (std::vector<std::string>{"https://scada.example", "*"}));
  EXPECT_EQ(c.http.max_connections, 64U);
  EXPECT_EQ(c.http.max_connections_per_address, 8U);
  const Config d = parse_config("", "gw.yaml");
  EXPECT_TRUE(d.http.host_names.empty());
  EXPECT_EQ(d.http.max_connections, 256U);
  EXPECT_EQ(d.http.max_connections_per_address, 32U);
  EXPECT_THAT(config_error("http:\n  host-names: [gw.example:8080]\n"),
              HasSubstr("gw.yaml:2: http.host-names[0]: 'gw.example:8080' is not a host name or IP address"));
  EXPECT_THAT(config_error("http:\n  host-names: ['http://gw.example']\n"), HasSubstr("http.host-names[0]"));
  EXPECT_THAT(config_error("http:\n  allowed-origins: [scada.example]\n"),
              HasSubstr("http.allowed-origins[0]: 'scada.example' is not an origin like https://host:port"));
  EXPECT_THAT(config_error("http:\n  allowed-origins: ['https://scada.example/app']\n"),
              HasSubstr("http.allowed-origins[0]"));
  EXPECT_THAT(config_error("http: {max-connections: 0}\n"), HasSubstr("http.max-connections: 0 is out of range"));
}

TEST(Config, RolesOfCallersWithoutToken) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  // Loopback without tokens: local callers are trusted (as before tokens).
  EXPECT_EQ(merge(Config{}, cli).http.anonymous_role(), Role::Admin);
  Config with = merge(parse_config("http:\n  tokens:\n    - {name: a, role: viewer, sha256: "
                                   "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08}\n"
                                   "  rate-limit: {requests-per-second: 5, burst: 10}\n"
                                   "mqtt: {uri: tcp://b:1883, requests-role: viewer}\n",
                                   "gw.yaml"),
                      cli);
  EXPECT_EQ(with.http.anonymous_role(), Role::None);
  EXPECT_EQ(with.mqtt.requests_role, Role::Viewer);
  EXPECT_EQ(with.http.rate_limit, 5.0);
  EXPECT_EQ(with.http.rate_burst, 10.0);
  EXPECT_THAT(config_error("mqtt: {uri: tcp://b:1883, requests-role: root}\n"),
              HasSubstr("mqtt.requests-role: 'root' is not viewer, operator or admin or none"));
  EXPECT_THAT(config_error("http: {rate-limit: {per-minute: 3}}\n"), HasSubstr("per-minute"));
}

// Issue 12, item 8 (contract "MQTT topics"): requests without a token act
// with mqtt.requests-role, default none, also when no tokens are configured
// (the broker's users are not the gateway's local callers).
TEST(Config, TokenlessMqttRequestsAreRefusedUnlessConfigured) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  const Config plain = merge(parse_config("mqtt: {uri: tcp://b:1883}\n", "gw.yaml"), cli);
  EXPECT_EQ(plain.http.anonymous_role(), Role::Admin);  // loopback HTTP without tokens: unchanged
  EXPECT_EQ(plain.mqtt.requests_role, Role::None);
  const Config set = merge(parse_config("mqtt: {uri: tcp://b:1883, requests-role: operator}\n", "gw.yaml"), cli);
  EXPECT_EQ(set.mqtt.requests_role, Role::Operator);
  // The demo without tokens reads over MQTT, as the README's tour does; with
  // tokens, or with the key set, it is the configuration's.
  CliOptions demo;
  demo.demo = true;
  EXPECT_EQ(merge(Config{}, demo).mqtt.requests_role, Role::Viewer);
  EXPECT_EQ(merge(parse_config("mqtt: {uri: tcp://b:1883, requests-role: none}\n", "gw.yaml"), demo).mqtt.requests_role,
            Role::None);
  const Config demo_tokens = merge(parse_config("http:\n  tokens:\n    - {name: a, role: viewer, sha256: "
                                                "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08}\n",
                                                "gw.yaml"),
                                   demo);
  EXPECT_EQ(demo_tokens.mqtt.requests_role, Role::None);
}

TEST(Config, ReplyTopicsAreCheckedTopicFilters) {
  const Config c = parse_config("mqtt:\n  uri: tcp://b:1883\n  reply-topics: [plant/+/answers, 'ops/#']\n", "gw.yaml");
  EXPECT_EQ(c.mqtt.reply_topics, (std::vector<std::string>{"plant/+/answers", "ops/#"}));
  EXPECT_TRUE(parse_config("mqtt: {uri: tcp://b:1883}\n", "gw.yaml").mqtt.reply_topics.empty());  // the default rule
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://b:1883\n  reply-topics: [ok/reply, 'a/#/b']\n"),
              HasSubstr("gw.yaml:3: mqtt.reply-topics[1]: 'a/#/b' is not an MQTT topic filter: '#' must be a whole "
                        "level and the last one"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://b:1883\n  reply-topics: ['a/b+']\n"),
              HasSubstr("'a/b+' is not an MQTT topic filter: '+' must be a whole level"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://b:1883\n  reply-topics: []\n"),
              HasSubstr("mqtt.reply-topics: no topic filter (leave the key out for the default rule)"));
  EXPECT_THAT(config_error("mqtt:\n  uri: tcp://b:1883\n  reply-topics: a/reply\n"),
              HasSubstr("mqtt.reply-topics: expected a list"));
}

TEST(Config, LoadConfigReadsTheFile) {
  const auto path = std::filesystem::temp_directory_path() / "canopen-config-test.yaml";
  {
    std::ofstream out(path);
    out << "networks:\n  - interface: vcan0\n";
  }
  const Config c = load_config(path.string());
  ASSERT_EQ(c.networks.size(), 1U);
  EXPECT_EQ(c.networks[0].interface, "vcan0");
  std::filesystem::remove(path);
  try {
    load_config(path.string());
    ADD_FAILURE() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot be read"));
  }
}

// Contract "Remote configuration and maintenance": the program download
// route's own body limit (other bodies keep 1 MiB).
TEST(Config, MaxProgramBytes) {
  EXPECT_EQ(parse_config("gateway: {id: a}\n", "gw.yaml").http.max_program_bytes, 16u * 1024 * 1024);
  EXPECT_EQ(parse_config("http: {max-program-bytes: 65536}\n", "gw.yaml").http.max_program_bytes, 65536u);
  EXPECT_THAT(config_error("http: {max-program-bytes: 12}\n"), HasSubstr("max-program-bytes"));
}

TEST(Config, ExampleFileInDeployIsValid) {
  const Config c = load_config(std::string(CANOPEN_SOURCE_DIR) + "/deploy/gateway.example.yaml");
  EXPECT_FALSE(c.networks.empty());
}

// Under systemd's StateDirectory= the queue goes where systemd says. Where
// each directory came from is kept for messages.
TEST(Config, StateDirectoryFromSystemd) {
  CliOptions cli;
  cli.can_interfaces = {"can0"};
  ::setenv("STATE_DIRECTORY", "/var/lib/canopen-gateway-x:/var/lib/other", 1);
  const Config c = merge(Config{}, cli);
  ::unsetenv("STATE_DIRECTORY");
  EXPECT_EQ(c.state_dir, "/var/lib/canopen-gateway-x");
  EXPECT_EQ(c.mqtt.queue.dir, "/var/lib/canopen-gateway-x/mqtt-queue");
  EXPECT_THAT(c.state_dir_origin, HasSubstr("$STATE_DIRECTORY"));
  EXPECT_THAT(c.queue_dir_origin, HasSubstr("mqtt.queue.dir not set"));
  Config explicit_dir = parse_config("gateway: {state-dir: /srv/gw}\nmqtt:\n  uri: tcp://b:1\n  queue: {dir: q}\n",
                                     "/etc/gw/gw.yaml");
  ::setenv("STATE_DIRECTORY", "/var/lib/canopen-gateway-x", 1);
  const Config from_file = merge(explicit_dir, cli);
  ::unsetenv("STATE_DIRECTORY");
  EXPECT_EQ(from_file.state_dir, "/srv/gw");  // the file wins
  EXPECT_EQ(from_file.state_dir_origin, "/etc/gw/gw.yaml:1: gateway.state-dir");
  EXPECT_EQ(from_file.queue_dir_origin, "/etc/gw/gw.yaml:4: mqtt.queue.dir");
}

}  // namespace
// capture: {ring-seconds, max-bytes} per network (issue 18, contract "Bus
// trace and capture"): defaults 60 s and 16 MiB; bad values are refused.
TEST(Config, CaptureRingPerNetwork) {
  const auto c = parse_config(
      "networks:\n  - interface: can0\n    capture: {ring-seconds: 10, max-bytes: 1048576}\n  - interface: can1\n",
      "gw.yaml");
  ASSERT_EQ(c.networks.size(), 2u);
  EXPECT_EQ(c.networks[0].capture.ring_seconds, 10u);
  EXPECT_EQ(c.networks[0].capture.max_bytes, 1048576u);
  EXPECT_EQ(c.networks[1].capture.ring_seconds, 60u);
  EXPECT_EQ(c.networks[1].capture.max_bytes, 16u << 20);
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    capture: {ring-seconds: 4000}\n"),
              HasSubstr("gw.yaml:3: networks[0].capture.ring-seconds: 4000 is out of range 0..3600"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    capture: {max-bytes: 10}\n"),
              HasSubstr("networks[0].capture.max-bytes: 10 is out of range 65536..1073741824"));
  EXPECT_THAT(config_error("networks:\n  - interface: can0\n    capture: {seconds: 4}\n"),
              HasSubstr("networks[0].capture.seconds: unknown key"));
}

// history: {max-bytes} (issue 18, docs/reference/rest.md "GET .../history"):
// the PDO value history's cap for the whole gateway, default 64 MiB; 0 turns
// it off; anything else below 1 MiB or over 16 GiB is refused by name.
TEST(Config, HistoryMaxBytes) {
  EXPECT_EQ(parse_config("networks:\n  - interface: can0\n", "gw.yaml").history.max_bytes, 64u << 20);
  EXPECT_EQ(parse_config("history: {max-bytes: 0}\n", "gw.yaml").history.max_bytes, 0u);
  EXPECT_EQ(parse_config("history: {max-bytes: 268435456}\n", "gw.yaml").history.max_bytes, 256u << 20);
  EXPECT_THAT(config_error("history: {max-bytes: 1000}\n"),
              HasSubstr("gw.yaml:1: history.max-bytes: must be 0 (no history) or 1048576 (1 MiB) .. 17179869184 (16 GiB), "
                        "not 1000"));
  EXPECT_THAT(config_error("history: {max-bytes: 17179869185}\n"), HasSubstr("history.max-bytes: 17179869185 is out of range"));
  EXPECT_THAT(config_error("history: {max-bytes: -1}\n"), HasSubstr("history.max-bytes"));
  EXPECT_THAT(config_error("history: {window: 60}\n"), HasSubstr("history.window: unknown key (known here: max-bytes)"));
}

}  // namespace gateway
