// A fake core::Networks for tests of the request core and of the front
// ends that drive it (tests/unit/gateway/core, tests/unit/gateway/app/sparkplug_output):
// no App, no bus, no clock. SDO transfers wait in `pending` until the test
// answer()s them; node `described` has the EDS/DCF `desc` (by default the
// small one below; a test may replace both).
#pragma once

#include <algorithm>
#include <chrono>
#include <deque>
#include <memory>
#include <string>
#include <optional>
#include <span>
#include <vector>

#include "canopen/eds/eds.hpp"
#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/sdo/abort.hpp"
#include "core/request_core.hpp"

namespace gateway::core::test_support {

inline constexpr std::uint8_t kOwnNode = 127;
inline constexpr std::uint8_t kDescribed = 5;  // has the EDS below

// 1000h, and 6060h (INTEGER8, limits -1..10).
inline const char* kEds =
    "[FileInfo]\nFileName=t.eds\n[DeviceInfo]\nVendorName=Test\n"
    "[MandatoryObjects]\nSupportedObjects=1\n1=0x1000\n"
    "[1000]\nParameterName=Device type\nObjectType=0x7\nDataType=0x0007\nAccessType=ro\nDefaultValue=0\n"
    "[OptionalObjects]\nSupportedObjects=1\n1=0x6060\n"
    "[6060]\nParameterName=Modes of operation\nObjectType=0x7\nDataType=0x0002\nAccessType=rw\n"
    "LowLimit=-1\nHighLimit=10\nDefaultValue=0\n";

struct FakeNetworks final : Networks {
  FakeNetworks()
      : own(canopen::od::make_gateway_dictionary(kOwnNode, canopen::od::GatewayIdentity{}, {})),
        desc(canopen::eds::parse_device_description(kEds, "t.eds", kDescribed)) {}
  FakeNetworks(const char* eds, std::uint8_t node)
      : own(canopen::od::make_gateway_dictionary(kOwnNode, canopen::od::GatewayIdentity{}, {})),
        described(node),
        desc(canopen::eds::parse_device_description(eds, "t.eds", node)) {}

  std::uint32_t count() const override { return networks; }
  std::uint8_t own_node_id(std::uint32_t) const override { return kOwnNode; }
  const canopen::od::ObjectDictionary& own_dictionary(std::uint32_t) const override { return own; }
  std::error_code write_own(std::uint32_t, std::uint16_t index, std::uint8_t sub,
                            std::span<const std::uint8_t> data) override {
    return own.write(index, sub, data);
  }
  const canopen::eds::DeviceDescription* description(std::uint32_t, std::uint8_t node) const override {
    return node == described ? &desc : nullptr;
  }
  std::optional<canopen::can::BusState> bus_state(std::uint32_t) const override { return bus; }
  canopen::Result<canopen::sdo::RequestId> sdo_upload(std::uint32_t, canopen::sdo::Request r) override {
    if (queue_full) return canopen::Error{make_error_code(canopen::SdoAbort::NoSdoConnection), "queue full"};
    pending.push_back(std::move(r));
    return canopen::sdo::RequestId{pending.size()};
  }
  canopen::Result<canopen::sdo::RequestId> sdo_download(std::uint32_t, canopen::sdo::Request r,
                                                        canopen::Bytes data) override {
    downloaded.push_back(data);
    return sdo_upload(1, std::move(r));
  }
  void send_nmt(std::uint32_t net, canopen::NmtCommand c, std::uint8_t node) override {
    nmt.push_back({net, c, node});
  }
  const canopen::pdo::PdoConfig* rpdo_config(std::uint32_t, std::uint8_t, std::uint16_t) const override {
    return nullptr;
  }
  std::error_code write_rpdo(std::uint32_t, std::uint8_t, std::uint16_t, std::span<const canopen::MappedValue>,
                             const canopen::Bytes*, canopen::Bytes&) override {
    return {};
  }
  void send_sync(std::uint32_t, std::optional<std::uint8_t> counter) override { syncs.push_back(counter); }
  bool has_pdo_table(std::uint32_t, std::uint8_t node) const override { return node == described; }
  std::error_code read_pdo_config(std::uint32_t, std::uint8_t,
                                  std::function<void(const canopen::pdo::PdoReadReport&)>) override {
    return {};
  }
  std::error_code lss(std::uint32_t, const LssStep& step, std::function<void(const LssOutcome&)> done) override {
    if (lss_refuse) return lss_refuse;
    lss_pending.push_back({step, std::move(done)});
    return {};
  }
  bool node_in_use(std::uint32_t, std::uint8_t node) const override {
    return node == kOwnNode || std::find(in_use.begin(), in_use.end(), node) != in_use.end();
  }
  std::error_code dcf_read(std::uint32_t, std::uint8_t node, TransferDone done) override {
    if (transfer_refuse) return transfer_refuse;
    transfers.push_back({"dcf-read", node, {}, 0, {}, std::move(done)});
    return {};
  }
  std::error_code dcf_apply(std::uint32_t, std::uint8_t node, const canopen::eds::DeviceDescription& dcf, bool store,
                            bool reset, TransferDone done) override {
    if (transfer_refuse) return transfer_refuse;
    transfers.push_back({"dcf-apply", node, std::make_shared<canopen::eds::DeviceDescription>(dcf), 0, {},
                         std::move(done), store, reset});
    return {};
  }
  std::error_code program_download(std::uint32_t, std::uint8_t node, std::uint8_t program, canopen::Bytes image,
                                   TransferDone done) override {
    if (transfer_refuse) return transfer_refuse;
    transfers.push_back({"program", node, {}, program, std::move(image), std::move(done)});
    return {};
  }
  std::chrono::steady_clock::time_point now() const override { return t; }

  // Ends the oldest pending maintenance transfer with `o`.
  void transfer_answer(TransferOutcome o = {}) {
    auto p = std::move(transfers.front());
    transfers.pop_front();
    p.done(std::move(o));
  }

  // Ends the oldest pending LSS step with `o` (default: ok).
  void lss_answer(LssOutcome o = {}) {
    auto p = std::move(lss_pending.front());
    lss_pending.pop_front();
    p.done(o);
  }

  // Answers the oldest pending transfer.
  void answer(canopen::Bytes data = {}, std::error_code error = {}) {
    auto r = std::move(pending.front());
    pending.pop_front();
    canopen::sdo::TransferResult res;
    res.error = error;
    res.origin = error ? canopen::sdo::Origin::Remote : canopen::sdo::Origin::None;
    res.data = std::move(data);
    r.on_done(std::move(res));
  }

  std::uint32_t networks = 2;
  canopen::od::ObjectDictionary own;
  std::uint8_t described = kDescribed;
  canopen::eds::DeviceDescription desc;
  std::optional<canopen::can::BusState> bus = canopen::can::BusState::ErrorActive;
  bool queue_full = false;
  std::deque<canopen::sdo::Request> pending;
  std::vector<canopen::Bytes> downloaded;
  struct NmtSentFrame {
    std::uint32_t net;
    canopen::NmtCommand command;
    std::uint8_t node;
  };
  std::vector<NmtSentFrame> nmt;
  std::vector<std::optional<std::uint8_t>> syncs;
  std::chrono::steady_clock::time_point t{};
  struct PendingLss {
    LssStep step;
    std::function<void(const LssOutcome&)> done;
  };
  std::deque<PendingLss> lss_pending;
  std::error_code lss_refuse;      // lss() returns it (nothing pending)
  std::vector<std::uint8_t> in_use;  // besides the own node
  // Maintenance transfers (DCF read/apply, program download) waiting for transfer_answer().
  struct PendingTransfer {
    std::string kind;  // "dcf-read", "dcf-apply", "program"
    std::uint8_t node = 0;
    std::shared_ptr<const canopen::eds::DeviceDescription> dcf;
    std::uint8_t program = 0;
    canopen::Bytes image;
    TransferDone done;
    bool store = false, reset = false;  // dcf-apply
  };
  std::deque<PendingTransfer> transfers;
  std::error_code transfer_refuse;  // the maintenance calls return it (nothing pending)
};

}  // namespace gateway::core::test_support
