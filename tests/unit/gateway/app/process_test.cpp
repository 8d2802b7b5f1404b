// The process's checks before anything starts (app/process.hpp).
#include "app/process.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

namespace gateway {
namespace {

using ::testing::HasSubstr;

std::string uri_error(const Config& c) {
  try {
    check_mqtt_uris(c);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

// Issue 27 item 2: every broker of mqtt.uri's and sparkplug.uri's lists is
// checked as the client reads it, and named with where it came from.
TEST(Process, EveryBrokerOfAListIsChecked) {
  Config c;
  c.mqtt.enabled = true;
  c.mqtt.uri_origin = "gw.yaml:4: mqtt.uri";
  c.mqtt.server_uri = "tcp://a:1883";
  c.mqtt.standby_uris = {"mqtts://b", "ssl://c:8883"};
  EXPECT_EQ(uri_error(c), "");

  c.mqtt.standby_uris = {"mqtts://b", "http://c"};
  EXPECT_THAT(uri_error(c), HasSubstr("gw.yaml:4: mqtt.uri: MQTT URI must start with tcp://"));
  c.mqtt.standby_uris = {"tcp://"};
  EXPECT_THAT(uri_error(c), HasSubstr("without host"));
  c.mqtt.standby_uris = {"mqtt://a:1883"};
  EXPECT_THAT(uri_error(c), HasSubstr("'mqtt://a:1883' is the same broker as another URI of the list"));

  c.mqtt.standby_uris.clear();
  c.sparkplug.enabled = true;
  c.sparkplug.uri_origin = "gw.yaml:9: sparkplug.uri";
  c.sparkplug.mqtt.server_uri = "tcp://s1";
  c.sparkplug.mqtt.standby_uris = {"ftp://s2"};
  EXPECT_THAT(uri_error(c), HasSubstr("gw.yaml:9: sparkplug.uri: MQTT URI must start with"));
}

}  // namespace
}  // namespace gateway
