// Fuzzes the decoding side of issue 4's services with arbitrary frames and
// time steps: PDO receiver (node 5 described by the shipped CiA 401 EDS),
// NMT master (boot-up, heartbeat consumer, node guarding), EMCY, SYNC and
// TIME consumers. Invariants: the master only ever sends node
// guarding RTRs for the guarded node; events name nodes 1..127; a node is
// reported lost only after it was heard (a consumed node and, with
// monitoring without configuration, any node the master hears: watching
// starts with its first heartbeat), the guarded node also when it never
// answered the polls; nothing crashes, leaks or hits UB. A decoded PDO never carries more values than its mapping has
// entries, and claimed PDOs name node 5.
// fuzz-libs: canopen_nmt canopen_emcy canopen_sync canopen_time canopen_pdo
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <set>

#include "canopen/emcy/emcy.hpp"
#include "canopen/sync/sync.hpp"
#include "canopen/time/time.hpp"
#include "canopen/nmt/master.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/pdo/receiver.hpp"

namespace {

constexpr std::uint8_t kGuarded = 9;

// Built once: the consumers only read it, and building it costs milliseconds.
const canopen::od::ObjectDictionary& dictionary() {
  static const canopen::od::ObjectDictionary od = [] {
    auto d = canopen::od::make_gateway_dictionary(127, {});
    (void)d.set(0x1012, 0, canopen::Value::of_unsigned(canopen::DataType::Unsigned32, 0x80000100U));  // consume TIME
    (void)d.set(0x1007, 0, canopen::Value::of_unsigned(canopen::DataType::Unsigned32, 5000));         // SYNC window
    return d;
  }();
  return od;
}

const canopen::od::ObjectDictionary& io_module() {
  static const canopen::od::ObjectDictionary od =
      canopen::eds::load_device_description(CANOPEN_SOURCE_DIR "/deploy/eds/cia401-io-module.eds", 5).od;
  return od;
}

}  // namespace

// Input: records of 11 bytes: selector, CAN-ID low, CAN-ID high, 8 data
// bytes. Selector bits 0-1: 0/1 data frame, 2 remote frame, 3 time step of
// (selector >> 2) * 23 ms; bits 4-7: length (clamped to 8).
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bool bad = false;
  std::set<std::uint8_t> seen;
  auto check_node = [&](std::uint8_t node) {
    if (node < 1 || node > 127) bad = true;
  };
  canopen::nmt::NmtMaster master(
      [&](const canopen::can::Frame& f) {
        if (!(f.remote() && f.id == 0x700U + kGuarded)) bad = true;
      },
      [&](const canopen::EventBody& body, canopen::can::Frame::Clock::time_point) {
        if (const auto* s = std::get_if<canopen::NodeStateEvent>(&body)) {
          check_node(s->node);
          if (s->cause == canopen::NodeStateEvent::Cause::Lost && s->node != kGuarded && !seen.contains(s->node))
            bad = true;
          if (s->cause != canopen::NodeStateEvent::Cause::Lost) seen.insert(s->node);
        } else if (const auto* h = std::get_if<canopen::HeartbeatEvent>(&body)) {
          check_node(h->node);
          seen.insert(h->node);
        }
      });
  canopen::TimePoint now{};
  master.set_heartbeat_consumer(3, std::chrono::milliseconds(100));
  master.set_heartbeat_consumer(5, std::chrono::milliseconds(1000));
  master.set_node_guarding(kGuarded, std::chrono::milliseconds(50), 3, now);
  canopen::emcy::EmcyConsumer emcy({}, [&](const canopen::EmcyEvent& e) {
    check_node(e.node);
    if (e.description.empty()) bad = true;
  });
  canopen::sync::SyncConsumer sync(dictionary(), [](const canopen::SyncEvent&) {});
  canopen::pdo::PdoReceiver pdo([](const canopen::can::Frame&) {}, [&](canopen::PdoEvent e) {
    if (e.node != 0 && e.node != 5) bad = true;
    if (e.values.size() > 64) bad = true;
  });
  (void)pdo.add_node(5, io_module());
  pdo.set_sync_window([&sync](canopen::TimePoint t) { return sync.in_sync_window(t); });
  canopen::time::TimeConsumer time(dictionary(), [](const canopen::TimeEvent&) {});

  for (std::size_t i = 0; i + 11 <= size; i += 11) {
    const std::uint8_t sel = data[i];
    if ((sel & 3) == 3) {
      now += std::chrono::milliseconds((sel >> 2) * 23);
      if (now >= master.next_deadline()) master.on_time(now);
      continue;
    }
    canopen::can::Frame f;
    f.id = (static_cast<std::uint32_t>(data[i + 1]) | (static_cast<std::uint32_t>(data[i + 2]) << 8)) & 0x7FFU;
    f.len = static_cast<std::uint8_t>(std::min(sel >> 4, 8));
    f.set(canopen::can::FrameFlag::Remote, (sel & 3) == 2);
    std::memcpy(f.data.data(), data + i + 3, 8);
    master.on_frame(f, now);
    pdo.on_frame(f, now);
    emcy.on_frame(f, now);
    sync.on_frame(f, now);
    time.on_frame(f, now);
    (void)sync.in_sync_window(now);
  }
  if (bad) __builtin_trap();
  return 0;
}
