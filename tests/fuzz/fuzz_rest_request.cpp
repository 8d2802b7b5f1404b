// Fuzzes what the gateway decodes from REST and WebSocket clients, without
// a server: the first byte selects the decoder, the rest is its input.
//   0: a request target ("/api/v1/...?type=u8") through the Router with the
//      gateway's REST patterns, then the path parameter parsers and ?type=;
//   1/2: an SDO read, SDO write and NMT body in JSON / binary protobuf
//      (gateway/messages request_codec), typed with value_as();
//   3: an RPDO write body against an RPDO of the demo devices' EDS files;
//   4: a WebSocket filter message (EventFilter);
//   5: an LSS fastscan / configure / assign-all body (aux selects).
// Invariants: nothing crashes or throws; parsed numbers are in range; a
// parsed index or sub-index reads back from its canonical text; an accepted
// filter's canonical JSON is accepted again and canonical (a fixed point);
// an accepted LSS body has its numbers in range, a refused one says why.
// fuzz-libs: gateway_rest_parse gateway_http_core gateway_messages canopen_eds
// fuzz-seeds: tests/fuzz/corpus/rest_request
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "canopen/eds/eds.hpp"
#include "canopen/pdo/mapping.hpp"
#include "http/event_stream.hpp"
#include "messages/request_codec.hpp"
#include "rest/rest_parse.hpp"
#include "http/router.hpp"

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "invariant broken: %s\n", what);
    std::abort();
  }
}

// The REST routes' (method, pattern) as rest_api.cpp registers them.
const gateway::http::Router& router() {
  static const gateway::http::Router r = [] {
    gateway::http::Router out;
    const gateway::http::Handler none = [](const gateway::http::Request&, gateway::http::Responder) {};
    const std::string node = "/api/v1/networks/{net}/nodes/{node}";
    out.add("GET", "/api/v1/gateway", none);
    out.add("GET", "/api/v1/openapi.json", none);
    out.add("GET", "/metrics", none);
    out.add("GET", "/api/v1/networks/{net}", none);
    out.add("GET", "/api/v1/networks/{net}/nodes", none);
    out.add("GET", node, none);
    out.add("GET", node + "/sdo/{index}/{sub}", none);
    out.add("PUT", node + "/sdo/{index}/{sub}", none);
    out.add("POST", node + "/nmt", none);
    out.add("GET", node + "/od", none);
    out.add("GET", node + "/emcy", none);
    out.add("PUT", node + "/rpdo/{n}", none);
    out.add("POST", "/api/v1/networks/{net}/sync", none);
    out.add("POST", "/api/v1/networks/{net}/lss/fastscan", none);
    out.add("POST", "/api/v1/networks/{net}/lss/configure", none);
    out.add("POST", "/api/v1/networks/{net}/lss/assign-all", none);
    out.add("GET", "/api/v1/networks/{net}/lss/devices", none);
    return out;
  }();
  return r;
}

void fuzz_target(std::string_view text, std::uint8_t method_byte) {
  static constexpr const char* kMethods[] = {"GET", "PUT", "POST", "HEAD", "DELETE"};
  const char* method = kMethods[method_byte % 5];
  const auto q = text.find('?');
  const std::string_view path = text.substr(0, q);
  std::vector<std::string> segments;
  if (!path.empty() && path.front() == '/') {
    std::size_t start = 1;
    while (start <= path.size()) {
      const auto slash = path.find('/', start);
      const auto end = slash == std::string_view::npos ? path.size() : slash;
      segments.emplace_back(path.substr(start, end - start));
      start = end + 1;
    }
    if (path.size() == 1) segments.clear();
  }
  const auto m = router().match(method, segments);
  using Kind = gateway::http::Router::Match::Kind;
  if (m.kind == Kind::MethodNotAllowed) check(!m.allow.empty(), "405 without Allow");
  if (m.kind != Kind::Found) return;
  check(m.handler != nullptr, "match without handler");
  for (const auto& [name, value] : m.params) {
    check(!value.empty(), "empty path parameter");
    if (name == "net" || name == "node" || name == "n") {
      if (auto v = gateway::rest::parse_decimal(value)) check(*v <= 999'999'999U, "decimal out of range");
    } else if (name == "index") {
      if (auto v = gateway::parse_index_text(value)) {
        char canon[8];
        std::snprintf(canon, sizeof canon, "%04X", static_cast<unsigned>(*v));
        check(gateway::parse_index_text(canon) == v, "index does not read back");
      }
    } else if (name == "sub") {
      if (auto v = gateway::parse_sub_index_text(value))
        check(gateway::parse_sub_index_text(std::to_string(*v)) == v, "sub-index does not read back");
    }
  }
  if (q != std::string_view::npos) {
    // Query as the server splits it (no percent-decoding here: that is Boost.URL's).
    std::string_view query = text.substr(q + 1);
    while (!query.empty()) {
      const auto amp = query.find('&');
      const auto pair = query.substr(0, amp);
      const auto eq = pair.find('=');
      if (eq != std::string_view::npos && pair.substr(0, eq) == "type") {
        if (auto t = canopen::parse_type_name(pair.substr(eq + 1))) check(!canopen::cia309_name(*t).empty(), "type");
      }
      if (amp == std::string_view::npos) break;
      query = query.substr(amp + 1);
    }
  }
}

void fuzz_bodies(std::string_view body, bool protobuf) {
  for (bool require_address : {true, false}) {
    if (auto r = gateway::parse_sdo_read(body, protobuf, require_address); r && require_address)
      check(r->index.has_value() && r->sub.has_value(), "read without address");
    if (auto w = gateway::parse_sdo_write(body, protobuf, require_address)) {
      check(!w->value.is_null(), "write without value");
      if (require_address) check(w->index.has_value() && w->sub.has_value(), "write without address");
      using canopen::DataType;
      for (auto t : {DataType::Boolean, DataType::Integer8, DataType::Unsigned16, DataType::Integer24,
                     DataType::Unsigned32, DataType::Integer64, DataType::Unsigned64, DataType::Real32,
                     DataType::Real64, DataType::VisibleString, DataType::OctetString, DataType::UnicodeString,
                     DataType::TimeOfDay, DataType::TimeDifference, DataType::Domain}) {
        (void)w->value_as(w->type.value_or(t));
      }
    }
  }
  if (auto n = gateway::parse_nmt(body, protobuf))
    check(gateway::nmt_command_from_name(gateway::nmt_command_name(n->command)) == n->command, "nmt name");
}

struct Rpdos {
  std::vector<canopen::eds::DeviceDescription> devices;
  std::vector<std::pair<std::size_t, canopen::pdo::PdoConfig>> pdos;  // (device, RPDO)
};

const Rpdos& rpdos() {
  static const Rpdos r = [] {
    Rpdos out;
    for (const char* file : {"/deploy/eds/cia402-drive.eds", "/deploy/eds/cia401-io-module.eds"}) {
      std::ifstream in(std::string(CANOPEN_SOURCE_DIR) + file);
      std::stringstream text;
      text << in.rdbuf();
      out.devices.push_back(canopen::eds::parse_device_description(text.str(), file, 5));
    }
    for (std::size_t d = 0; d < out.devices.size(); ++d)
      for (auto& p : canopen::pdo::read_all(out.devices[d].od, canopen::pdo::Direction::Receive))
        out.pdos.emplace_back(d, std::move(p));
    check(!out.pdos.empty(), "the demo EDS files have RPDOs");
    return out;
  }();
  return r;
}

void fuzz_rpdo(std::string_view body, std::uint8_t which) {
  const auto& r = rpdos();
  const auto& [device, pdo] = r.pdos[which % r.pdos.size()];
  std::string error;
  auto parsed = gateway::rest::parse_rpdo_body(body, pdo, r.devices[device].od, "RPDO", error);
  if (!parsed) {
    check(!error.empty(), "refused without a reason");
    return;
  }
  if (parsed->raw) {
    check(parsed->raw->size() == pdo.byte_length(), "raw of the wrong length");
    check(parsed->values.empty(), "raw and values");
  } else {
    check(!parsed->values.empty(), "no values");
    for (const auto& v : parsed->values) check(canopen::holds_its_type(v.value), "value of another type");
  }
}

void fuzz_filter(std::string_view text, std::uint8_t probe) {
  gateway::http::EventFilter f;
  std::string error;
  if (!f.parse(text, error)) {
    check(!error.empty(), "filter refused without a reason");
    return;
  }
  const auto canon = f.to_json();
  gateway::http::EventFilter again;
  check(again.parse(canon, error), "canonical filter refused");
  check(again.to_json() == canon, "canonical filter not a fixed point");
  gateway::EncodedEvent ev;
  ev.kind = static_cast<gateway::EventKind>(probe % 10);
  ev.network = probe / 10U % 3U;
  ev.node = static_cast<std::uint8_t>(probe % 7U == 0 ? 0 : 5);
  check(f.matches(ev) == again.matches(ev), "canonical filter matches differently");
}

// The LSS bodies (contract "LSS master"): accepted ones within the ranges
// the contract gives, refused ones with a reason.
void fuzz_lss(std::string_view body, std::uint8_t which) {
  std::string error;
  switch (which % 3) {
    case 0: {
      auto f = gateway::rest::parse_lss_fastscan(body, error);
      if (f && f->timeout) check(f->timeout->count() >= 1 && f->timeout->count() <= 10000, "fastscan timeout range");
      check(f.has_value() || !error.empty(), "fastscan body refused without a reason");
      break;
    }
    case 1: {
      auto c = gateway::rest::parse_lss_configure(body, error);
      if (c) check(c->node_id >= 1 && c->node_id <= 127, "configure nodeId range");
      check(c.has_value() || !error.empty(), "configure body refused without a reason");
      break;
    }
    default: {
      auto a = gateway::rest::parse_lss_assign_all(body, error);
      if (a) check(a->first_node_id >= 1 && a->first_node_id <= 127, "assign-all firstNodeId range");
      check(a.has_value() || !error.empty(), "assign-all body refused without a reason");
      break;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::uint8_t selector = data[0];
  const std::uint8_t aux = data[1];
  const std::string_view input(reinterpret_cast<const char*>(data + 2), size - 2);
  switch (selector % 6) {
    case 0:
      fuzz_target(input, aux);
      break;
    case 1:
      fuzz_bodies(input, false);
      break;
    case 2:
      fuzz_bodies(input, true);
      break;
    case 3:
      fuzz_rpdo(input, aux);
      break;
    case 4:
      fuzz_filter(input, aux);
      break;
    default:
      fuzz_lss(input, aux);
      break;
  }
  return 0;
}
