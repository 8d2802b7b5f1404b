// Test rig for the master-side maintenance services: an SdoClient (the
// gateway's side) and a simulated device (canopen::Device on an EDS
// dictionary, with the simulator's CiA 302-3 program objects and 1010h/1011h
// wired to the Device) on the in-memory bus, run with the fake clock.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "canopen/can/memory_bus.hpp"
#include "canopen/clock.hpp"
#include "canopen/device.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/sdo/client.hpp"
#include "sim/device_objects.hpp"

namespace canopen::test {

inline std::string source_path(const std::string& rel) { return std::string(CANOPEN_SOURCE_DIR) + "/" + rel; }

struct DeviceRig {
  static constexpr std::uint8_t kNode = 5;

  explicit DeviceRig(const std::string& eds_file = "deploy/eds/cia401-io-module.eds", sdo::ClientConfig cc = {})
      : eds(eds::load_device_description(source_path(eds_file), kNode)),
        device_od(eds.od),
        client(cc, [this](const can::Frame& f) {
          master_frames.push_back(f);
          master_ep->send(f);
        }) {
    sim::install_program_objects(device_od);
    od::install_store_restore(
        device_od, [this](std::uint8_t g) { return device->store_parameters(g); },
        [this](std::uint8_t g) { return device->restore_default_parameters(g); });
    device_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs)
        if (device && (!device_filter || device_filter(f))) device->on_frame(f, clock.now());
    });
    master_ep->on_frames([this](std::span<const can::Frame> fs) {
      for (const auto& f : fs) client.on_frame(f, clock.now());
    });
    DeviceConfig cfg;
    cfg.node_id = kNode;
    device = std::make_unique<Device>(device_od, cfg, [this](const can::Frame& f) { device_ep->send(f); });
    device->start(clock.now());
    bus.deliver();
    master_frames.clear();
  }

  // Runs the client and the device until `end`, delivering frames after every step.
  void run_for(Duration d) {
    const TimePoint end = clock.now() + d;
    for (;;) {
      bus.deliver();
      const TimePoint next = std::min(client.next_deadline(), device->next_deadline());
      if (next > end) break;
      if (next > clock.now()) clock.advance_to(next);
      if (client.next_deadline() <= clock.now()) client.on_time(clock.now());
      if (device->next_deadline() <= clock.now()) device->on_time(clock.now());
    }
    clock.advance_to(end);
    bus.deliver();
  }

  // Frames the master sent with this CAN-ID whose first bytes are `prefix`.
  std::size_t count_sent(std::uint32_t id, std::vector<std::uint8_t> prefix) const {
    return static_cast<std::size_t>(std::count_if(master_frames.begin(), master_frames.end(), [&](const can::Frame& f) {
      return f.id == id && f.len >= prefix.size() && std::equal(prefix.begin(), prefix.end(), f.data.begin());
    }));
  }

  FakeClock clock;
  can::MemoryBus bus;
  std::unique_ptr<can::MemoryEndpoint> device_ep = bus.attach("device");
  std::unique_ptr<can::MemoryEndpoint> master_ep = bus.attach("master");
  eds::DeviceDescription eds;
  od::ObjectDictionary device_od;
  std::unique_ptr<Device> device;
  std::vector<can::Frame> master_frames;
  std::function<bool(const can::Frame&)> device_filter;  // false: the device does not hear the frame
  sdo::SdoClient client;
};

}  // namespace canopen::test
