#include "messages/json_input.hpp"

#include <boost/json/parse.hpp>
#include <boost/json/value.hpp>

namespace gateway {

std::optional<boost::json::object> parse_json_object(std::string_view text, std::string_view what,
                                                     std::string_view shape, std::string& error) {
  boost::system::error_code ec;
  boost::json::value v = boost::json::parse(text, ec);
  if (ec) {
    error = std::string(what) + " is not valid JSON: " + ec.message();
    return std::nullopt;
  }
  if (auto* obj = v.if_object()) return std::move(*obj);
  error = std::string(what) + " must be a JSON object" + std::string(shape);
  return std::nullopt;
}

}  // namespace gateway
