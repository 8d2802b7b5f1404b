// App::CoreNetworks: the request core's view of the networks
// (core::Networks), on each NetworkUnit's services.
//
// Thread safety: io thread only (App's).
#include <memory>

#include "app/app.hpp"
#include "canopen/eds/eds.hpp"
#include "canopen/master/dcf_transfer.hpp"
#include "canopen/master/program_download.hpp"
#include "canopen/network.hpp"
#include "canopen/sdo/abort.hpp"
#include "app/network_unit.hpp"

namespace gateway {

// The request core's view of the networks: each call on the network's
// services (which report their new deadlines to the driver themselves).
struct App::CoreNetworks final : core::Networks {
  explicit CoreNetworks(App& a) : app(a) {}
  App& app;
  Net& n(std::uint32_t net) const { return *app.nets_[net - 1]; }

  std::uint32_t count() const override { return static_cast<std::uint32_t>(app.nets_.size()); }
  std::uint8_t own_node_id(std::uint32_t net) const override { return n(net).cfg.node_id; }
  const canopen::od::ObjectDictionary& own_dictionary(std::uint32_t net) const override { return *n(net).own_od; }
  std::error_code write_own(std::uint32_t net, std::uint16_t index, std::uint8_t sub,
                            std::span<const std::uint8_t> data) override {
    Net& x = n(net);
    return x.own_od->write(index, sub, data);  // the own node follows (DeadlineSource)
  }
  const canopen::eds::DeviceDescription* description(std::uint32_t net, std::uint8_t node) const override {
    return app.description(net, node);
  }
  std::optional<canopen::can::BusState> bus_state(std::uint32_t net) const override { return app.bus_state(net); }
  canopen::Result<canopen::sdo::RequestId> sdo_upload(std::uint32_t net, canopen::sdo::Request r) override {
    Net& x = n(net);
    return x.network->sdo().upload(std::move(r), x.now());
  }
  canopen::Result<canopen::sdo::RequestId> sdo_download(std::uint32_t net, canopen::sdo::Request r,
                                                        canopen::Bytes data) override {
    Net& x = n(net);
    return x.network->sdo().download(std::move(r), std::move(data), x.now());
  }
  void send_nmt(std::uint32_t net, canopen::NmtCommand command, std::uint8_t node) override {
    Net& x = n(net);
    x.network->send_nmt(command, node);
  }
  const canopen::pdo::PdoConfig* rpdo_config(std::uint32_t net, std::uint8_t node,
                                             std::uint16_t number) const override {
    return app.rpdo_config(net, node, number);
  }
  std::error_code write_rpdo(std::uint32_t net, std::uint8_t node, std::uint16_t number,
                             std::span<const canopen::MappedValue> values, const canopen::Bytes* raw,
                             canopen::Bytes& sent) override {
    Net& x = n(net);
    auto& tx = x.network->rpdo();
    const auto now = x.now();
    if (auto ec = raw != nullptr ? tx.set_raw(node, number, *raw, now) : tx.set_values(node, number, values, now))
      return ec;
    if (const auto* p = tx.payload(node, number)) sent = *p;
    return {};
  }
  void send_sync(std::uint32_t net, std::optional<std::uint8_t> counter) override {
    n(net).local->send_sync(counter);  // 1005h's COB-ID, to the bus and the master side
  }
  bool has_pdo_table(std::uint32_t net, std::uint8_t node) const override {
    return n(net).network->pdo_config().has_node(node);
  }
  std::error_code read_pdo_config(std::uint32_t net, std::uint8_t node,
                                  std::function<void(const canopen::pdo::PdoReadReport&)> done) override {
    Net& x = n(net);
    return x.network->read_pdo_config(node, std::move(done), x.now());
  }
  // The core's LSS steps on the network's LSS master (canopen/lss/master.hpp),
  // its errors as the core's outcomes.
  std::error_code lss(std::uint32_t net, const core::LssStep& step,
                      std::function<void(const core::LssOutcome&)> done) override {
    namespace lss = canopen::lss;
    using S = core::LssOutcome::Status;
    auto outcome = [](const canopen::Error& e) {
      core::LssOutcome o;
      o.detail = e.detail.empty() ? e.code.message() : e.detail;
      if (e.code == lss::LssError::Timeout) {
        o.status = S::timeout;
      } else if (e.code == lss::LssError::NoUnconfiguredSlave) {
        o.status = S::none_found;
      } else if (auto b = lss::slave_error_byte(e.code)) {
        o.status = S::refused;
        o.error = *b;
      } else {
        o.status = S::failed;
      }
      return o;
    };
    auto ack = [done, outcome](canopen::Result<lss::Ack> r) { done(r ? core::LssOutcome{} : outcome(r.error())); };
    auto value = [done, outcome](auto r) {
      if (!r) return done(outcome(r.error()));
      core::LssOutcome o;
      o.value = *r;
      done(o);
    };
    Net& x = n(net);
    auto& m = x.network->lss();
    const auto now = x.now();
    if (const auto* g = std::get_if<core::LssSwitchGlobal>(&step))
      return m.switch_state_global(g->configuration ? lss::Mode::Configuration : lss::Mode::Waiting, ack, now);
    if (const auto* sel = std::get_if<core::LssSwitchSelective>(&step))
      return m.switch_state_selective(sel->address, ack, now);
    if (const auto* id = std::get_if<core::LssSetNodeId>(&step)) return m.configure_node_id(id->node_id, ack, now);
    if (const auto* bt = std::get_if<core::LssSetBitTiming>(&step))
      return m.configure_bit_timing(bt->table, bt->index, ack, now);
    if (const auto* act = std::get_if<core::LssActivateBitTiming>(&step))
      return m.activate_bit_timing(act->delay_ms, ack, now);
    if (std::holds_alternative<core::LssStore>(step)) return m.store_configuration(ack, now);
    if (const auto* q = std::get_if<core::LssInquiry>(&step)) {
      if (*q == core::LssInquiry::node_id)
        return m.inquire_node_id([value](canopen::Result<std::uint8_t> r) { value(std::move(r)); }, now);
      return m.inquire_identity(static_cast<lss::Part>(*q),
                                [value](canopen::Result<std::uint32_t> r) { value(std::move(r)); }, now);
    }
    const auto& f = std::get<core::LssFastscan>(step);
    lss::FastscanRequest req;
    if (f.timeout) req.step_timeout = *f.timeout;
    return m.fastscan(
        req,
        [done, outcome](const lss::FastscanResult& r) {
          if (r.error) return done(outcome(canopen::Error{r.error, {}}));
          core::LssOutcome o;
          o.address = r.identity;
          done(o);
        },
        now);
  }
  // Remote maintenance on the network's services (canopen/master/
  // dcf_transfer.hpp, program_download.hpp), their reports as the core's
  // TransferOutcome. The services emit the `transfer` events themselves.
  static std::error_code start_error(std::error_code ec) {
    if (ec == canopen::master::TransferError::Busy) return std::make_error_code(std::errc::device_or_resource_busy);
    if (ec == canopen::master::TransferError::NothingToTransfer) return std::make_error_code(std::errc::invalid_argument);
    return ec;
  }
  static core::ObjectOutcome outcome_of(const canopen::master::ObjectResult& r) {
    return core::ObjectOutcome{r.index, r.sub, r.error, r.detail};
  }
  std::error_code dcf_read(std::uint32_t net, std::uint8_t node, core::TransferDone done) override {
    const auto* desc = app.description(net, node);
    if (desc == nullptr) return make_error_code(canopen::SdoAbort::NoSuchObject);
    // The DCF is written from the EDS as it was at the start: a copy, as a
    // new EDS for the node may come meanwhile.
    auto eds = std::make_shared<const canopen::eds::DeviceDescription>(*desc);
    Net& x = n(net);
    return start_error(x.network->read_dcf(
        node, *eds,
        [eds, node, done = std::move(done)](const canopen::master::DcfReadReport& r) {
          core::TransferOutcome o;
          o.error = r.stopped;
          o.detail = r.detail;
          for (const auto& f : r.failed) o.objects.push_back(outcome_of(f));
          if (!o.error) {
            o.text = canopen::master::write_dcf(*eds, node, r.values);
            o.read = r.values.size();
          }
          done(std::move(o));
        },
        x.now()));
  }
  std::error_code dcf_apply(std::uint32_t net, std::uint8_t node, const canopen::eds::DeviceDescription& dcf,
                            bool store, bool reset, core::TransferDone done) override {
    Net& x = n(net);
    canopen::master::DcfApplyOptions options;
    options.store = store;
    options.reset = reset;
    return start_error(x.network->apply_dcf(
        node, dcf, options,
        [done = std::move(done)](const canopen::master::DcfApplyReport& r) {
          core::TransferOutcome o;
          o.error = r.stopped;
          o.detail = r.detail;
          for (const auto& w : r.objects) o.objects.push_back(outcome_of(w));
          o.stored = r.stored;
          o.reset = r.reset;
          if (r.store_error) o.store_error = outcome_of(*r.store_error);
          done(std::move(o));
        },
        x.now()));
  }
  std::error_code program_download(std::uint32_t net, std::uint8_t node, std::uint8_t program, canopen::Bytes image,
                                   core::TransferDone done) override {
    Net& x = n(net);
    canopen::master::ProgramDownloadOptions options;
    options.program = program;
    return start_error(x.network->download_program(
        node, options, std::move(image),
        [done = std::move(done)](const canopen::master::ProgramDownloadReport& r) {
          core::TransferOutcome o;
          o.error = r.error;
          o.remote = r.origin == canopen::sdo::Origin::Remote;
          o.detail = r.detail;  // names the step and its object ("clear program (1F51h sub 1 := 3): ...")
          o.bytes = r.bytes;
          o.identification = r.identification;
          done(std::move(o));
        },
        x.now()));
  }
  bool node_in_use(std::uint32_t net, std::uint8_t node) const override {
    const Net& x = n(net);
    if (node == x.cfg.node_id) return true;
    for (const auto& c : x.cfg.nodes)
      if (c.id == node) return true;
    return app.cache().node(net, node) != nullptr;  // heard on the bus
  }
};

std::unique_ptr<core::Networks> App::make_core_networks(App& app) { return std::make_unique<CoreNetworks>(app); }

}  // namespace gateway
