// The canopen-gateway process after its command line: the configuration
// (file merged with the flags and checked), the logger, the networks
// (compose_networks()), the App, every front end (front_ends.hpp: HTTP/REST
// and the WebSocket event stream, the CiA 309-3 ASCII server), the start,
// and on SIGINT/SIGTERM the orderly stop. main.cpp parses the command line
// and calls run_gateway().
//
// Thread safety: call once, from the main thread; it runs the io_context
// on that thread until the gateway stopped.
#pragma once

#include <string>

#include "cli.hpp"
#include "config/config.hpp"

namespace gateway {

// Exit codes besides 0 (stopped by a signal) and 1 (an unexpected exception).
inline constexpr int kExitConfig = 2;          // configuration, usage, TLS files, a listener
inline constexpr int kExitCanUnavailable = 3;  // a CAN interface that cannot be opened

// Runs the gateway `opts` describe until SIGINT or SIGTERM and returns the
// exit code: 0 after the stop, kExitConfig or kExitCanUnavailable (with one
// line on stderr, print_error()) when it cannot start. Throws what else goes
// wrong (main answers 1).
int run_gateway(const CliOptions& opts);

// The broker URIs of mqtt.uri and of the Sparkplug edge node (sparkplug.uri
// or mqtt's), every one of a list, as the MQTT client will read them: a bad
// scheme, no host, or one broker given twice (mqtt://a and tcp://a) throws
// ConfigError naming where the URI came from (--mqtt, file:line: key).
void check_mqtt_uris(const Config& c);

// "canopen-gateway: error: <msg>" on stderr, one line: whatever the message
// quotes cannot break it or drive the terminal.
void print_error(const std::string& msg);

}  // namespace gateway
