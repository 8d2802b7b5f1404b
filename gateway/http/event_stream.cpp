#include "http/event_stream.hpp"

#include <algorithm>
#include <boost/json/serialize.hpp>
#include <boost/json/value.hpp>

#include "messages/json_input.hpp"

namespace gateway::http {

namespace {

// Reads an array of integers in [0, max] into `out`.
template <class T>
bool read_ints(const boost::json::value& v, std::uint64_t max, std::vector<T>& out, std::string_view key,
               std::string& error) {
  const auto* arr = v.if_array();
  if (!arr) {
    error = std::string(key) + " must be an array of integers";
    return false;
  }
  out.clear();
  for (const auto& e : *arr) {
    std::uint64_t n = 0;
    if (e.is_int64() && e.get_int64() >= 0) {
      n = static_cast<std::uint64_t>(e.get_int64());
    } else if (e.is_uint64()) {
      n = e.get_uint64();
    } else {
      error = std::string(key) + " must be an array of non-negative integers";
      return false;
    }
    if (n > max) {
      error = std::string(key) + ": " + std::to_string(n) + " is out of range 0.." + std::to_string(max);
      return false;
    }
    out.push_back(static_cast<T>(n));
  }
  return true;
}

}  // namespace

bool EventFilter::parse(std::string_view text, std::string& error) {
  const auto obj = parse_json_object(text, "filter", "", error);
  if (!obj) return false;
  std::vector<std::uint32_t> networks;
  std::vector<std::uint8_t> nodes;
  std::uint32_t kinds = 0;
  for (const auto& kv : *obj) {
    if (kv.key() == "networks") {
      if (!read_ints(kv.value(), 0xFFFFFFFFu, networks, "networks", error)) return false;
    } else if (kv.key() == "nodes") {
      if (!read_ints(kv.value(), 127, nodes, "nodes", error)) return false;
    } else if (kv.key() == "kinds") {
      const auto* arr = kv.value().if_array();
      if (!arr) {
        error = "kinds must be an array of strings";
        return false;
      }
      for (const auto& e : *arr) {
        EventKind k{};
        const auto* s = e.if_string();
        if (!s || !event_kind_from_string(std::string_view(*s), k)) {
          error = "kinds: unknown kind " + boost::json::serialize(e);
          return false;
        }
        kinds |= 1u << static_cast<unsigned>(k);
      }
    } else {
      error = "unknown filter key \"" + std::string(kv.key()) + "\" (expected networks, nodes, kinds)";
      return false;
    }
  }
  networks_ = std::move(networks);
  nodes_ = std::move(nodes);
  kinds_ = kinds;
  return true;
}

bool EventFilter::matches(const EncodedEvent& ev) const {
  if (kinds_ != 0 && (kinds_ & (1u << static_cast<unsigned>(ev.kind))) == 0) return false;
  if (!networks_.empty() && std::find(networks_.begin(), networks_.end(), ev.network) == networks_.end())
    return false;
  if (!nodes_.empty() && std::find(nodes_.begin(), nodes_.end(), ev.node) == nodes_.end()) return false;
  return true;
}

std::string EventFilter::to_json() const {
  boost::json::object o;
  boost::json::array nets, nodes, kinds;
  for (auto n : networks_) nets.emplace_back(n);
  for (auto n : nodes_) nodes.emplace_back(n);
  for (unsigned k = 0; k < 32; ++k)
    if (kinds_ & (1u << k)) kinds.emplace_back(to_string(static_cast<EventKind>(k)));
  o["networks"] = std::move(nets);
  o["nodes"] = std::move(nodes);
  o["kinds"] = std::move(kinds);
  return boost::json::serialize(o);
}

bool SendQueue::thinnable(const Item& item) {
  return item.event && (item.event->kind == EventKind::Tpdo || item.event->kind == EventKind::Heartbeat);
}

bool SendQueue::full(std::size_t extra_bytes) const {
  return items_.size() >= limits_.max_messages || bytes_ + extra_bytes > limits_.max_bytes;
}

SendQueue::Result SendQueue::push(Item item, std::chrono::steady_clock::time_point now) {
  const std::size_t n = item.payload().size();
  Result result = Result::Queued;
  if (!items_.empty() && full(n)) {
    if (!stalled_) {
      stalled_ = true;
      stalled_since_ = now;
    } else if (now - stalled_since_ > limits_.stall_timeout) {
      return Result::Close;
    }
    // Drop oldest thinnable messages until the new one fits.
    while (full(n) && thinnable_count_ > 0) {
      auto it = std::find_if(items_.begin(), items_.end(), [](const Item& i) { return thinnable(i); });
      bytes_ -= it->payload().size();
      --thinnable_count_;
      items_.erase(it);
      ++dropped_;
    }
    if (!items_.empty() && full(n)) {
      if (!thinnable(item)) return Result::Close;
      ++dropped_;
      return Result::Thinned;
    }
    result = Result::Thinned;
  }
  bytes_ += n;
  if (thinnable(item)) ++thinnable_count_;
  items_.push_back(std::move(item));
  return result;
}

SendQueue::Item SendQueue::pop() {
  Item it = std::move(items_.front());
  items_.pop_front();
  bytes_ -= it.payload().size();
  if (thinnable(it)) --thinnable_count_;
  note_drained();
  return it;
}

void SendQueue::note_drained() {
  if (stalled_ && items_.size() <= limits_.max_messages / 2 && bytes_ <= limits_.max_bytes / 2) stalled_ = false;
}

void SendQueue::clear() {
  items_.clear();
  bytes_ = 0;
  thinnable_count_ = 0;
}

}  // namespace gateway::http
