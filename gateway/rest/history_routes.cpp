#include "rest/history_routes.hpp"

#include <boost/json/array.hpp>
#include <boost/json/object.hpp>
#include <boost/json/serialize.hpp>
#include <charconv>
#include <chrono>

#include "canopen/eds/eds.hpp"
#include "core/format.hpp"
#include "messages/json_text.hpp"
#include "rest/route_checks.hpp"

namespace gateway {

namespace {

namespace json = boost::json;
using http::Request;
using http::Responder;
using http::Response;

std::optional<std::uint32_t> parse_hex_digits(std::string_view s, std::size_t digits) {
  if (s.size() != digits) return std::nullopt;
  std::uint32_t v = 0;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v, 16);
  if (ec != std::errc() || p != s.data() + s.size()) return std::nullopt;
  return v;
}

// A stored float as the double with the float's shortest digits
// (12.3f -> 12.3, not 12.300000190734863): what was recorded, no more.
double tidy(float f) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, f);
  double d = static_cast<double>(f);
  std::from_chars(buf, r.ptr, d);
  return d;
}

void get_history(const status::View& status, const Request& req, Responder respond) {
  if (accepts_only_protobuf(req)) return respond(json_only_refusal());
  std::uint32_t net = 0;
  std::uint8_t node = 0;
  if (auto err = check_net(status, req, net)) return respond(std::move(*err));
  if (auto err = check_node(req, node, false)) return respond(std::move(*err));
  std::int64_t window = history::kDefaultWindow;
  if (auto w = req.query_param("window")) {
    const auto n = core::parse_decimal(*w);
    if (!n || *n < history::kMinWindow || *n > history::kMaxWindow)
      return respond(Response::problem(400, "window must be a number of seconds " + std::to_string(history::kMinWindow) +
                                                ".." + std::to_string(history::kMaxWindow) + ", not '" +
                                                std::string(*w) + "'"));
    window = *n;
  }
  std::vector<history::ObjectId> objects;
  if (auto o = req.query_param("objects")) {
    std::string error;
    auto parsed = parse_history_objects(*o, error);
    if (!parsed) return respond(Response::problem(400, error));
    objects = std::move(*parsed);
  }
  const auto* h = status.value_history();
  if (h == nullptr) return respond(Response::problem(404, "history is off (history.max-bytes: 0)"));

  const auto now = std::chrono::floor<std::chrono::seconds>(std::chrono::system_clock::now());
  const auto result = h->query(net, node, objects, window, now);
  const auto* desc = status.description(net, node);
  json::array series;
  for (const auto& s : result.series) {
    json::object o;
    o["object"] = core::hex_number(s.object.index, 4) + ":" + core::hex_number(s.object.sub, 2);
    o["index"] = s.object.index;
    o["sub"] = s.object.sub;
    std::string name = s.name;
    canopen::DataType type = s.type;
    json::value unit = nullptr;
    json::value factor = nullptr;
    if (desc != nullptr) {
      // The node's description as configured now names the object; its
      // unit and scale are the vendor's (EntryFacts), else raw.
      if (const auto* e = desc->od.find(s.object.index, s.object.sub)) {
        if (!e->name.empty()) name = e->name;
        type = e->type;
      }
      const auto facts = desc->facts(s.object.index, s.object.sub);
      if (!facts.unit.empty()) unit = facts.unit;
      if (facts.factor) factor = *facts.factor;
    }
    o["name"] = name;
    o["type"] = canopen::standard_name(type);
    o["unit"] = std::move(unit);
    o["factor"] = std::move(factor);
    json::array t, mean, min, max;
    t.reserve(s.points.size());
    mean.reserve(s.points.size());
    min.reserve(s.points.size());
    max.reserve(s.points.size());
    for (const auto& p : s.points) {
      t.emplace_back(p.t);
      if (p.gap) {
        mean.emplace_back(nullptr);
        min.emplace_back(nullptr);
        max.emplace_back(nullptr);
      } else {
        mean.emplace_back(tidy(p.mean));
        min.emplace_back(tidy(p.min));
        max.emplace_back(tidy(p.max));
      }
    }
    o["t"] = std::move(t);
    o["mean"] = std::move(mean);
    o["min"] = std::move(min);
    o["max"] = std::move(max);
    series.emplace_back(std::move(o));
  }
  json::object body;
  body["network"] = net;
  body["node"] = node;
  body["window"] = window;
  body["resolution"] = result.resolution;
  body["from"] = timestamp_text(now - std::chrono::seconds(window));
  body["to"] = timestamp_text(now);
  body["series"] = std::move(series);
  json::object memory;
  memory["bytes"] = h->bytes();
  memory["maxBytes"] = h->max_bytes();
  memory["objects"] = h->objects();
  memory["refusedObjects"] = h->refused_objects();
  body["memory"] = std::move(memory);
  respond(Response::json(json::serialize(body)));
}

}  // namespace

std::optional<std::vector<history::ObjectId>> parse_history_objects(std::string_view text, std::string& error) {
  std::vector<history::ObjectId> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = text.find(',', start);
    const std::string_view item = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    const auto colon = item.find(':');
    const auto index = colon == std::string_view::npos ? std::nullopt : parse_hex_digits(item.substr(0, colon), 4);
    const auto sub = colon == std::string_view::npos ? std::nullopt : parse_hex_digits(item.substr(colon + 1), 2);
    if (!index || !sub) {
      error = "objects must be a comma-separated list of IIII:SS in hex (e.g. 6401:01,6000:01), not '" +
              std::string(item) + "' in '" + std::string(text) + "'";
      return std::nullopt;
    }
    out.push_back({static_cast<std::uint16_t>(*index), static_cast<std::uint8_t>(*sub)});
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

void register_history_routes(http::HttpServer& server, const status::View& status) {
  server.add_route("GET", "/api/v1/networks/{net}/nodes/{node}/history",
                   [s = &status](const Request& req, Responder respond) { get_history(*s, req, std::move(respond)); });
}

}  // namespace gateway
