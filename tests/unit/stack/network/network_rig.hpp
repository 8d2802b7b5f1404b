// Test rig for canopen::Network against a real device: the gateway's side
// (a Network on its own dictionary) and one canopen::Device, node kNode,
// whose dictionary starts as an EDS of deploy/eds (`device_od` is what the
// device really holds), on the in-memory bus, run with the fake clock.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "canopen/can/memory_bus.hpp"
#include "canopen/clock.hpp"
#include "canopen/device.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/network.hpp"
#include "canopen/od/gateway_dictionary.hpp"

namespace canopen::test {

struct NetworkRig {
  static constexpr std::uint8_t kNode = 5;

  // `eds_file` relative to the source tree. The device is off until power_on().
  explicit NetworkRig(const std::string& eds_file)
      : eds(eds::load_device_description(std::string(CANOPEN_SOURCE_DIR) + "/" + eds_file, kNode)),
        device_od(eds.od) {
    dev_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs)
        if (device) device->on_frame(f, clock.now());
    });
    gw_ep->on_frames([this](std::span<const can::Frame> fs) {
      if (!gateway_listens) return;
      for (const auto& f : fs) net.on_frame(f, clock.now());
    });
  }
  // Powers the device on (boot-up) with what `device_od` holds now.
  void power_on() {
    DeviceConfig cfg;
    cfg.node_id = kNode;
    device = std::make_unique<Device>(device_od, cfg, [this](const can::Frame& f) { dev_ep->send(f); });
    device->start(clock.now());
  }
  // Runs the network and the device until `d` from now, delivering frames after every step.
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      bus.deliver();
      TimePoint next = net.next_deadline();
      if (device) next = std::min(next, device->next_deadline());
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      if (net.next_deadline() <= clock.now()) net.on_time(clock.now());
      if (device && device->next_deadline() <= clock.now()) device->on_time(clock.now());
    }
    clock.advance_to(end);
    bus.deliver();
  }
  // One SDO download through the gateway's client (as REST/MQTT do); the
  // device's answer.
  std::error_code write(std::uint16_t index, std::uint8_t sub, Bytes data) {
    std::optional<std::error_code> result;
    sdo::Request r;
    r.node = kNode;
    r.index = index;
    r.sub = sub;
    r.on_done = [&](sdo::TransferResult&& res) { result = res.error; };
    EXPECT_TRUE(net.sdo().download(std::move(r), std::move(data), clock.now()));
    run_for(std::chrono::milliseconds(20));
    EXPECT_TRUE(result.has_value()) << "no answer";
    return result.value_or(make_error_code(SdoAbort::Timeout));
  }
  // The network's events of one kind, with their seq, in order.
  template <typename T>
  std::vector<std::pair<std::uint64_t, T>> events_of() const {
    std::vector<std::pair<std::uint64_t, T>> out;
    for (const auto& e : events)
      if (const auto* b = std::get_if<T>(&e.body)) out.emplace_back(e.seq, *b);
    return out;
  }
  template <typename T>
  std::vector<T> bodies() const {
    std::vector<T> out;
    for (auto& [seq, b] : events_of<T>()) out.push_back(std::move(b));
    return out;
  }

  FakeClock clock;
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> gw_ep = bus.attach("gateway");
  std::unique_ptr<can::MemoryEndpoint> dev_ep = bus.attach("device");
  od::ObjectDictionary own = od::make_gateway_dictionary(127, {});
  eds::DeviceDescription eds;
  od::ObjectDictionary device_od;
  std::unique_ptr<Device> device;
  std::vector<Event> events;
  // false: the gateway is not running yet (it hears nothing).
  bool gateway_listens = true;
  std::vector<can::Frame> sent;  // every frame the network put on the bus
  Network net{own,
              [this](const can::Frame& f) {
                sent.push_back(f);
                gw_ep->send(f);
              },
              [this](const Event& e) { events.push_back(e); }};
};

}  // namespace canopen::test
