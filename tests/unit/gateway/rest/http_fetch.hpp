// A blocking HTTP/1.1 client for tests: one request per connection
// ("Connection: close"), run on its own thread while the test thread runs
// the server's io_context. Header-only, no Beast, so it tests the server
// from the outside.
#pragma once

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/read.hpp>
#include <boost/asio/read_until.hpp>
#include <boost/asio/write.hpp>
#include <boost/json.hpp>
#include <cctype>
#include <cstdint>
#include <string>
#include <vector>

namespace gateway::testing {

struct HttpReply {
  int status = 0;
  std::string head;  // status line and header fields, lower-cased
  std::string content_type;
  std::string body;
  boost::json::value parsed;  // the body as JSON; null when it is not
  const boost::json::value& json() const { return parsed; }
  bool has_header(const std::string& lower_name_and_value) const {
    return head.find("\r\n" + lower_name_and_value) != std::string::npos;
  }
};

// Sends `method target` with `headers` ("Name: value"; Host defaults to
// 127.0.0.1:<port>) and `body`; reads
// until the server closes (or, for a 101, until the end of the header).
inline HttpReply fetch(std::uint16_t port, const std::string& method, const std::string& target,
                       const std::string& body, const std::vector<std::string>& headers) {
  namespace asio = boost::asio;
  asio::io_context io;
  asio::ip::tcp::socket s(io);
  s.connect({asio::ip::make_address("127.0.0.1"), port});
  std::string req = method + " " + target + " HTTP/1.1\r\n";
  bool upgrade = false, host = false;
  for (const auto& h : headers) {
    req += h + "\r\n";
    upgrade = upgrade || h.rfind("Upgrade:", 0) == 0;
    host = host || h.rfind("Host:", 0) == 0;
  }
  if (!host) req += "Host: 127.0.0.1:" + std::to_string(port) + "\r\n";
  if (!upgrade) req += "Connection: close\r\n";
  if (!body.empty() || method == "PUT" || method == "POST")
    req += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  req += "\r\n" + body;
  asio::write(s, asio::buffer(req));
  std::string all;
  boost::system::error_code ec;
  if (upgrade) {
    asio::read_until(s, asio::dynamic_buffer(all), "\r\n\r\n", ec);
    if (all.rfind("HTTP/1.1 101", 0) != 0) asio::read(s, asio::dynamic_buffer(all), ec);
  } else {
    asio::read(s, asio::dynamic_buffer(all), ec);  // until the server closes
  }
  HttpReply r;
  const auto head_end = all.find("\r\n\r\n");
  if (all.size() < 12 || head_end == std::string::npos) return r;
  r.status = std::stoi(all.substr(9, 3));
  r.head = all.substr(0, head_end);
  for (char& c : r.head) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (auto p = r.head.find("\r\ncontent-type: "); p != std::string::npos) {
    auto e = r.head.find("\r\n", p + 2);
    r.content_type = all.substr(p + 16, (e == std::string::npos ? r.head.size() : e) - p - 16);
  }
  r.body = all.substr(head_end + 4);
  if (r.head.find("transfer-encoding: chunked") != std::string::npos) {  // de-chunk
    std::string out;
    std::size_t pos = 0;
    while (pos < r.body.size()) {
      const auto eol = r.body.find("\r\n", pos);
      if (eol == std::string::npos) break;
      const auto n = std::stoul(r.body.substr(pos, eol - pos), nullptr, 16);
      if (n == 0) break;
      out += r.body.substr(eol + 2, n);
      pos = eol + 2 + n + 2;
    }
    r.body = out;
  }
  boost::system::error_code jec;
  auto v = boost::json::parse(r.body, jec);
  if (!jec) r.parsed = std::move(v);
  return r;
}

}  // namespace gateway::testing
