#include "trace/trace_stream.hpp"

#include <boost/json/serialize.hpp>
#include <boost/json/value.hpp>
#include <cstdio>
#include <ctime>

#include "core/format.hpp"
#include "messages/json_input.hpp"

namespace gateway::trace {

std::string frame_json(const Traced& t, std::string_view decoded, Service service) {
  const auto& f = t.frame;
  const auto us =
      std::chrono::duration_cast<std::chrono::microseconds>(f.timestamp.time_since_epoch()).count();
  std::time_t secs = static_cast<std::time_t>(us / 1000000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char ts[96];
  std::snprintf(ts, sizeof ts, "%04d-%02d-%02dT%02d:%02d:%02d.%06lldZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<long long>(us % 1000000));
  std::string s;
  s.reserve(128 + decoded.size());
  s += "{\"t\":\"";
  s += ts;
  s += "\",\"id\":" + std::to_string(f.id);
  s += f.extended() ? ",\"ext\":true" : ",\"ext\":false";
  s += f.remote() ? ",\"rtr\":true" : ",\"rtr\":false";
  s += f.fd() ? ",\"fd\":true" : ",\"fd\":false";
  s += t.dir == Direction::Rx ? ",\"dir\":\"rx\"" : ",\"dir\":\"tx\"";
  s += ",\"data\":\"";
  core::append_hex(s, f.payload());
  s += "\",\"decoded\":";
  s += boost::json::serialize(boost::json::value(boost::json::string_view(decoded.data(), decoded.size())));
  s += ",\"service\":\"";
  s += service.service;  // a fixed token, nothing to escape
  s += '"';
  if (service.node != 0) s += ",\"node\":" + std::to_string(service.node);
  s += '}';
  return s;
}

bool IdFilter::parse(std::string_view text, std::string& error) {
  const auto obj = parse_json_object(text, "filter", ": {\"ids\": [[from, to], ...]}", error);
  if (!obj) return false;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> ranges;
  for (const auto& kv : *obj) {
    if (kv.key() != "ids") {
      error = "unknown filter key \"" + std::string(kv.key()) + "\" (expected ids)";
      return false;
    }
    const auto* arr = kv.value().if_array();
    if (!arr) {
      error = "ids must be an array of [from, to] pairs";
      return false;
    }
    if (arr->size() > kMaxRanges) {
      error = "ids: at most " + std::to_string(kMaxRanges) + " ranges";
      return false;
    }
    for (const auto& e : *arr) {
      const auto* pair = e.if_array();
      std::uint64_t bounds[2] = {0, 0};
      bool ok = pair && pair->size() == 2;
      for (std::size_t i = 0; ok && i < 2; ++i) {
        const auto& n = (*pair)[i];
        if (n.is_int64() && n.get_int64() >= 0) bounds[i] = static_cast<std::uint64_t>(n.get_int64());
        else if (n.is_uint64()) bounds[i] = n.get_uint64();
        else ok = false;
      }
      if (!ok) {
        error = "ids: " + boost::json::serialize(e) + " is not a [from, to] pair of non-negative integers";
        return false;
      }
      if (bounds[0] > bounds[1] || bounds[1] > canopen::can::kMaxExtendedId) {
        error = "ids: [" + std::to_string(bounds[0]) + ", " + std::to_string(bounds[1]) +
                "] must have from <= to <= 536870911 (1FFFFFFFh)";
        return false;
      }
      ranges.emplace_back(static_cast<std::uint32_t>(bounds[0]), static_cast<std::uint32_t>(bounds[1]));
    }
  }
  ranges_ = std::move(ranges);
  return true;
}

bool IdFilter::matches(std::uint32_t id) const {
  if (ranges_.empty()) return true;
  for (const auto& [from, to] : ranges_)
    if (id >= from && id <= to) return true;
  return false;
}

std::string IdFilter::to_json() const {
  std::string s = "{\"ids\":[";
  for (std::size_t i = 0; i < ranges_.size(); ++i) {
    if (i) s += ',';
    s += "[" + std::to_string(ranges_[i].first) + "," + std::to_string(ranges_[i].second) + "]";
  }
  return s + "]}";
}

bool TraceQueue::push_frame(Message m) {
  const std::string lost = lost_pending_ ? "{\"lost\":" + std::to_string(lost_pending_) + "}" : std::string();
  if (!fits(lost.empty() ? 1 : 2, m->size() + lost.size())) {
    ++lost_pending_;
    ++lost_total_;
    return false;
  }
  if (!lost.empty()) {
    lost_pending_ = 0;
    push_control(lost);
  }
  bytes_ += m->size();
  items_.push_back(std::move(m));
  return true;
}

void TraceQueue::push_control(std::string text) {
  bytes_ += text.size();
  items_.push_back(std::make_shared<const std::string>(std::move(text)));
}

Message TraceQueue::take_lost() {
  if (lost_pending_ == 0) return nullptr;
  auto m = std::make_shared<const std::string>("{\"lost\":" + std::to_string(lost_pending_) + "}");
  lost_pending_ = 0;
  return m;
}

Message TraceQueue::pop() {
  Message m = std::move(items_.front());
  items_.pop_front();
  bytes_ -= m->size();
  return m;
}

}  // namespace gateway::trace
