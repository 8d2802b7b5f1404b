// The server's accept loop: the per-address and total connection limits,
// eviction of idle connections, and stop().
#include <chrono>
#include <iterator>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "http/http_session.hpp"
#include "http/server_impl.hpp"

namespace gateway::http {

namespace {

// A refusal of connections is logged once per episode: again only after
// this long without refusals for that address (or for the full server).
constexpr auto kRefusalQuiet = std::chrono::seconds(60);

// The key of a client address for the per-address limit (an IPv4 client of
// a dual-stack listener counts as its IPv4 address).
std::string address_key(const net::ip::address& a) {
  if (a.is_v6() && a.to_v6().is_v4_mapped()) return net::ip::make_address_v4(net::ip::v4_mapped, a.to_v6()).to_string();
  return a.to_string();
}

}  // namespace

std::string endpoint_string(const tcp::endpoint& ep) {
  const auto addr = ep.address();
  std::string s = addr.is_v6() ? "[" + addr.to_string() + "]" : addr.to_string();
  return s + ":" + std::to_string(ep.port());
}

void HttpServer::Impl::do_accept() {
  auto self = shared_from_this();
  acceptor.async_accept([self](error_code ec, tcp::socket socket) { self->on_accept(ec, std::move(socket)); });
}

void HttpServer::Impl::on_accept(error_code ec, tcp::socket socket) {
  if (stopped || ec == net::error::operation_aborted) return;
  if (ec) {
    // Out of descriptors and the like: retry later instead of spinning.
    if (log) log->warn("http: accept failed: " + ec.message());
    auto self = shared_from_this();
    accept_timer.expires_after(std::chrono::milliseconds(100));
    accept_timer.async_wait([self](error_code e) {
      if (!e && !self->stopped) self->do_accept();
    });
    return;
  }
  counters.accepted.fetch_add(1, std::memory_order_relaxed);
  error_code pec;
  const auto ep = socket.remote_endpoint(pec);
  error_code ignored;
  if (pec) {  // gone already
    socket.close(ignored);
    return do_accept();
  }
  std::string address = address_key(ep.address());
  const auto held = per_address.find(address);
  // At an address's cap its longest idle connection makes room (every
  // client behind one reverse proxy shares an address); refused only when
  // all of that address's connections are busy.
  const bool at_cap = cfg.max_connections_per_address > 0 && held != per_address.end() &&
                      held->second >= cfg.max_connections_per_address;
  const bool made_room = at_cap && evict_idle(&address);
  if (at_cap && !made_room) {
    counters.rejected_per_address.fetch_add(1, std::memory_order_relaxed);
    socket.close(ignored);
    note_refusal(address, "client " + address + " has " + std::to_string(held->second) +
                              " connections open (http.max-connections-per-address): closing its new ones");
    return do_accept();
  }
  // (A connection evicted for this address also makes room in the total.)
  if (!made_room && counters.active.load(std::memory_order_relaxed) >= cfg.max_connections && !evict_idle()) {
    counters.rejected_full.fetch_add(1, std::memory_order_relaxed);
    socket.close(ignored);
    note_refusal("", std::to_string(cfg.max_connections) +
                         " connections open, none idle (http.max-connections): closing new ones");
    return do_accept();
  }
  std::string peer = endpoint_string(ep);
  auto slot = std::make_shared<AddressSlot>(shared_from_this(), std::move(address));
  socket.set_option(tcp::no_delay(true), ignored);
  counters.active.fetch_add(1, std::memory_order_relaxed);
  start_http_session(shared_from_this(), std::move(slot), std::move(socket), std::move(peer));
  do_accept();
}

// Closes the connection that has waited longest for a request, if any.
bool HttpServer::Impl::evict_idle(const std::string* key) {
  std::shared_ptr<Closable> oldest;
  std::uint64_t since = 0;
  for (auto& [id, w] : connections) {
    auto c = w.lock();
    if (!c || (key && !c->from_address(*key))) continue;
    if (auto t = c->idle_since(); t && (!oldest || *t < since)) {
      oldest = std::move(c);
      since = *t;
    }
  }
  if (!oldest) return false;
  counters.evicted_idle.fetch_add(1, std::memory_order_relaxed);
  debug(key ? "client " + *key + " at http.max-connections-per-address: closing its longest idle connection for a new one"
            : std::string("server full: closing the longest idle connection for a new one"));
  oldest->shutdown();
  return true;
}

// Logs the first refusal of an episode; the counters have every one.
void HttpServer::Impl::note_refusal(const std::string& key, const std::string& message) {
  const auto now = std::chrono::steady_clock::now();
  for (auto it = refusing.begin(); it != refusing.end();)
    it = now - it->second > kRefusalQuiet ? refusing.erase(it) : std::next(it);
  const auto [it, fresh] = refusing.try_emplace(key, now);
  it->second = now;
  if (fresh && log)
    log->warn("http: " + message + " (counted in /metrics; logged again after a minute without refusals)");
}

void HttpServer::Impl::stop() {
  if (stopped) return;
  stopped = true;
  error_code ignored;
  acceptor.close(ignored);
  accept_timer.cancel();
  std::vector<std::shared_ptr<Closable>> all;
  for (auto& [id, w] : connections)
    if (auto c = w.lock()) all.push_back(std::move(c));
  for (auto& c : all) c->shutdown();
}

}  // namespace gateway::http
