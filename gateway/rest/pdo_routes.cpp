// The PDO configuration in effect (issue 11): GET .../pdo from the status
// view, POST .../pdo/read through the request core, then as GET.
#include "rest/routes.hpp"

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>

#include "canopen/pdo/config_reader.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/pdo/remote_config.hpp"
#include "canopen/sdo/abort.hpp"
#include "messages/json_text.hpp"
#include "messages/request_codec.hpp"
#include "rest/route_checks.hpp"

namespace gateway::rest {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

const char* direction_text(canopen::pdo::Direction d) {
  return d == canopen::pdo::Direction::Transmit ? "tpdo" : "rpdo";
}

json::object pdo_json(const canopen::pdo::RemotePdo& p, const canopen::Result<canopen::pdo::PdoConfig>& cfg) {
  using canopen::pdo::Direction;
  const auto& c = p.parameters.comm;
  json::object o;
  o["direction"] = direction_text(p.key.direction);
  o["number"] = p.key.number;
  o["commIndex"] = canopen::pdo::comm_index(p.key.direction, p.key.number);
  o["mappingIndex"] = canopen::pdo::mapping_index(p.key.direction, p.key.number);
  o["cobId"] = c.cob_id.can_id();
  o["cobIdRaw"] = c.cob_id.raw;
  o["enabled"] = c.cob_id.valid();
  o["rtrAllowed"] = c.cob_id.rtr_allowed();
  o["extended"] = c.cob_id.extended();
  o["transmissionType"] = c.transmission_type;
  o["inhibitTime"] = c.inhibit_time;
  o["eventTimer"] = c.event_timer;
  o["syncStart"] = c.sync_start;
  const unsigned count = p.parameters.count;
  o["kind"] = count == 0xFE ? "sam-mpdo" : count == 0xFF ? "dam-mpdo" : "normal";
  json::array mapping;
  if (cfg) {
    for (const auto& e : cfg->entries) {
      json::object m;
      m["index"] = e.index;
      m["subIndex"] = e.sub;
      m["bits"] = e.bits;
      m["name"] = e.name;
      m["type"] = std::string(canopen::cia309_name(e.type));
      m["dummy"] = e.dummy;
      mapping.push_back(std::move(m));
    }
    o["length"] = cfg->byte_length();
  } else {
    // Not resolvable: the raw entries as the device has them, and why.
    for (unsigned i = 1; i <= count && i <= canopen::pdo::kMaxMappedEntries; ++i) {
      const auto it = p.parameters.entries.find(static_cast<std::uint8_t>(i));
      if (it == p.parameters.entries.end()) break;
      const auto e = canopen::pdo::MappingEntry::from_raw(it->second);
      json::object m;
      m["index"] = e.index;
      m["subIndex"] = e.sub;
      m["bits"] = e.bits;
      mapping.push_back(std::move(m));
    }
    o["error"] = cfg.error().detail;
  }
  o["mapping"] = std::move(mapping);
  o["source"] = std::string(canopen::pdo::to_string(p.source));
  if (!p.read_error.empty()) o["readError"] = p.read_error;
  return o;
}

json::array pdos_json(const canopen::pdo::RemotePdoTable& table, std::uint8_t node) {
  json::array list;
  for (const auto* p : table.pdos(node)) list.push_back(pdo_json(*p, table.resolve(node, p->key)));
  return list;
}

// The node's PDO table, or the 404 when it has none (no EDS/DCF).
const canopen::pdo::RemotePdoTable* node_pdo_table(const Context& ctx, std::uint32_t net, std::uint8_t node,
                                                   std::optional<Response>& err) {
  const auto* table = ctx.status.pdo_config(net);
  if (table == nullptr || !table->has_node(node))
    err = problem_response(404, "node " + std::to_string(node) + " on network " + std::to_string(net) +
                                    " has no EDS/DCF, so its PDOs are not decoded");
  return err ? nullptr : table;
}

}  // namespace

void get_pdo(const Context& ctx, const Request& req, Responder respond) {
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(ctx.status, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  std::optional<Response> err;
  const auto* table = node_pdo_table(ctx, net, node, err);
  if (table == nullptr) return respond(std::move(*err));
  json::object o;
  o["network"] = net;
  o["node"] = node;
  o["pdos"] = pdos_json(*table, node);
  respond(json_response(o));
}

void read_pdo(const Context& ctx, const Request& req, Responder respond) {
  const auto net = path_network(req, respond);
  if (!net) return;
  std::string error;
  const auto node = path_node(req, false, error);
  core::Command command = undecodable(core::Operation::pdo_config_read, 0, error, true);
  if (node) command = core::PdoConfigRead{*node};
  const status::View* a = &ctx.status;
  ctx.core.execute(
      core_request(req, *net, std::move(command)),
      json_result<core::PdoConfigReport>(std::move(respond), [a](const core::PdoConfigReport& report) {
        json::array read;
        for (const auto& p : report.report.pdos) {
          json::object o;
          o["direction"] = direction_text(p.key.direction);
          o["number"] = p.key.number;
          o["ok"] = p.parameters.has_value();
          if (!p.parameters) {
            o["error"] = p.detail;
            if (&p.error.category() == &canopen::sdo_abort_category()) {
              o["abortCode"] = detail::abort_code_text(static_cast<std::uint32_t>(p.error.value()));
            }
          }
          read.push_back(std::move(o));
        }
        json::object out;
        out["network"] = report.network;
        out["node"] = report.node;
        out["summary"] = report.report.summary();
        out["read"] = std::move(read);
        out["pdos"] = pdos_json(*a->pdo_config(report.network), report.node);
        return out;
      }));
}

}  // namespace gateway::rest
