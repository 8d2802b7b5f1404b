#include "messages/problem_json.hpp"

#include <boost/json/object.hpp>
#include <boost/json/serialize.hpp>

#include "canopen/types.hpp"
#include "core/format.hpp"
#include "http_status.hpp"

namespace gateway {

namespace {

std::string utf8(std::string_view s) { return canopen::is_utf8(s) ? std::string(s) : canopen::latin1_to_utf8(s); }

}  // namespace

std::string problem_json(const core::Problem& p, std::string_view correlation_id) {
  boost::json::object o;
  o["type"] = p.type.empty() ? std::string("about:blank") : utf8(p.type);
  o["title"] = p.title.empty() ? std::string(reason_phrase(p.status)) : utf8(p.title);
  o["status"] = p.status;
  o["detail"] = utf8(p.detail);
  if (p.abort_code) o["abortCode"] = core::abort_code_text(*p.abort_code);
  if (!correlation_id.empty()) o["correlationId"] = utf8(correlation_id);
  return boost::json::serialize(o);
}

}  // namespace gateway
