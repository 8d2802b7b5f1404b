#include "ascii/ascii_server.hpp"

#include <sys/stat.h>
#include <sys/un.h>

#include <algorithm>
#include <cstring>
#include <array>
#include <deque>
#include <filesystem>
#include <list>
#include <stdexcept>
#include <system_error>

#include <boost/asio/generic/stream_protocol.hpp>
#include <boost/asio/basic_socket_acceptor.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>

#include "ascii/ascii_listen.hpp"
#include "core/request_core.hpp"
#include "log.hpp"

namespace gateway::ascii {

namespace asio = boost::asio;
using Protocol = asio::generic::stream_protocol;

namespace {

constexpr std::size_t kMaxPendingLines = 64;  // complete lines waiting per client before it is no longer read
constexpr std::size_t kWriteChunk = 64 * 1024;
constexpr std::size_t kPrintChunk = 3 * 4096;  // raw bytes printed per step (base64 needs multiples of 3)

// The address parsed, as Asio endpoints.
struct Listen {
  bool unix_socket = false;
  std::string path;
  asio::ip::tcp::endpoint tcp;
};

std::optional<Listen> parse_listen(const std::string& text) {
  auto a = parse_listen_address(text);
  if (!a) return std::nullopt;
  Listen l;
  l.unix_socket = a->unix_socket;
  l.path = a->path;
  if (!l.unix_socket) l.tcp = asio::ip::tcp::endpoint(asio::ip::make_address(a->host), a->port);
  return l;
}

// The core's typed value for the bytes a write command parsed: the numeric
// datatypes typed (the core checks them against the EDS limits and the
// audit line shows the number), everything else as the bytes themselves.
canopen::Value core_value(Datatype t, const canopen::Bytes& data) {
  using DT = canopen::DataType;
  DT type = DT::Domain;
  switch (t) {
    case Datatype::b: type = data.size() == 1 && data[0] <= 1 ? DT::Boolean : DT::Unsigned8; break;
    case Datatype::i8: type = DT::Integer8; break;
    case Datatype::i16: type = DT::Integer16; break;
    case Datatype::i32: type = DT::Integer32; break;
    case Datatype::i64: type = DT::Integer64; break;
    case Datatype::u8:
    case Datatype::x8: type = DT::Unsigned8; break;
    case Datatype::u16:
    case Datatype::x16: type = DT::Unsigned16; break;
    case Datatype::u32:
    case Datatype::x32: type = DT::Unsigned32; break;
    case Datatype::u64:
    case Datatype::x64: type = DT::Unsigned64; break;
    case Datatype::r32: type = DT::Real32; break;
    case Datatype::r64: type = DT::Real64; break;
    case Datatype::os: type = DT::OctetString; break;
    default: type = DT::Domain; break;  // vs, us, d, hex: the bytes exactly as given
  }
  auto v = canopen::decode(type, data);
  if (!v) return canopen::Value::of_bytes(DT::Domain, data);
  return std::move(*v);
}

asio::ip::tcp::endpoint tcp_endpoint(const Protocol::endpoint& ep) {
  asio::ip::tcp::endpoint tcp;
  if (ep.size() <= sizeof(sockaddr_in6)) {
    std::memcpy(tcp.data(), ep.data(), ep.size());
    tcp.resize(ep.size());
  }
  return tcp;
}

// A refusal or failure of the core as CiA 309-3 answers it.
std::string problem_text(std::uint32_t seq, const core::Problem& p) {
  if (p.abort_code) return abort_response(seq, *p.abort_code);
  if (auto refused = role_refusal(seq, p.status, p.detail)) return *refused;  // not for this client's role
  switch (p.status) {
    case 404: return error_response(seq, Error::UnsupportedNet);
    case 400: return abort_response(seq, 0x06090030);  // a value the node's EDS/DCF does not allow
    default: return error_response(seq, Error::InternalState);  // 429 queue share, 503 bus down, ...
  }
}

}  // namespace

// ---- one connection ---------------------------------------------------------------

class Session;

struct Server::Impl : std::enable_shared_from_this<Impl> {
  Impl(asio::io_context& context, ServerConfig config, core::RequestCore& requests, Logger* logger)
      : io(context), cfg(std::move(config)), core(requests), log(logger) {}
  void accept();
  void remove(const std::shared_ptr<Session>& s);

  asio::io_context& io;
  ServerConfig cfg;
  core::RequestCore& core;
  Logger* log;
  std::optional<asio::basic_socket_acceptor<Protocol>> acceptor;
  Listen listen;
  std::uint16_t port = 0;
  LssHandler lss;
  std::list<std::shared_ptr<Session>> sessions;
  std::uint64_t next_id = 1;
  bool running = false;
};

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(std::weak_ptr<Server::Impl> srv, Protocol::socket sock, std::string peer, std::uint64_t id,
          const ServerConfig& cfg)
      : srv_(std::move(srv)),
        sock_(std::move(sock)),
        timer_(sock_.get_executor()),
        framer_(cfg.max_line),
        cfg_(cfg) {
    caller_.transport = core::Transport::ascii;
    caller_.authenticated = true;  // by the transport: loopback/unix, or allowed remote
    caller_.role = cfg.role;
    caller_.who = "ascii " + peer;
    caller_.key = "ascii:" + std::to_string(id);
  }

  std::size_t buffered() const { return out_.size() + (writing_ ? wbuf_.size() : 0); }

  void start() {
    last_activity_ = std::chrono::steady_clock::now();
    arm_timer();
    read_more();
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    boost::system::error_code ec;
    timer_.cancel();
    sock_.shutdown(Protocol::socket::shutdown_both, ec);
    sock_.close(ec);
    if (auto srv = srv_.lock()) srv->remove(shared_from_this());
  }

 private:
  // Marks activity without reading the clock (a system call on some
  // kernels, and this runs several times a command): the idle timer reads
  // it, every eighth of the timeout, so a connection closes between
  // idle_timeout and 9/8 of it after its last activity.
  void touch() { touched_ = true; }

  void arm_timer() {
    if (cfg_.idle_timeout.count() <= 0 || closed_) return;
    const auto tick = std::max<std::chrono::steady_clock::duration>(
        std::chrono::duration_cast<std::chrono::steady_clock::duration>(cfg_.idle_timeout) / 8,
        std::chrono::milliseconds(1));
    timer_.expires_after(tick);
    timer_.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec || self->closed_) return;
      const auto now = std::chrono::steady_clock::now();
      // A command the core is still running (an SDO transfer waits for its
      // own timeout) is not idleness; output that does not move is.
      const bool waiting_for_core = self->busy_ && !self->stream_;
      if (self->touched_ || waiting_for_core) {
        self->touched_ = false;
        self->last_activity_ = now;
      }
      if (now >= self->last_activity_ + self->cfg_.idle_timeout) return self->close();
      self->arm_timer();
    });
  }

  bool can_read() const {
    return !closed_ && !reading_ && !input_done_ && buffered() < cfg_.max_output &&
           pending_.size() < kMaxPendingLines;
  }

  void read_more() {
    if (!can_read()) return;
    reading_ = true;
    sock_.async_read_some(asio::buffer(rbuf_), [self = shared_from_this()](const boost::system::error_code& ec,
                                                                           std::size_t n) {
      self->reading_ = false;
      if (self->closed_) return;
      if (ec) {
        // End of input: what was sent is still answered, then the connection closes.
        self->input_done_ = true;
        if (ec != asio::error::eof) return self->close();
        self->process();
        return;
      }
      self->touch();
      std::vector<LineFramer::Item> items;
      self->framer_.feed(std::string_view(self->rbuf_.data(), n), items);
      for (auto& i : items) self->pending_.push_back(std::move(i));
      self->process();
    });
  }

  // Runs queued lines while no command is running and the output has room.
  void process() {
    while (!closed_ && !busy_ && !stream_ && !pending_.empty() && buffered() < cfg_.max_output) {
      auto item = std::move(pending_.front());
      pending_.pop_front();
      handle(item);
    }
    flush();
    read_more();
    maybe_close();
  }

  void handle(const LineFramer::Item& item) {
    if (item.too_long) {
      // The sequence number, when the line began with one.
      const auto p = parse_line(item.text, defaults_);
      out_ += error_response(p.seq.value_or(last_seq_), Error::OutOfMemory);
      if (p.seq) last_seq_ = *p.seq;
      return;
    }
    const Parsed p = parse_line(item.text, defaults_);
    if (p.seq) last_seq_ = *p.seq;
    switch (p.kind) {
      case Parsed::Kind::empty: out_ += empty_response(); return;
      case Parsed::Kind::error: out_ += error_response(p.seq.value_or(last_seq_), p.error); return;
      case Parsed::Kind::command: execute(p.line); return;
    }
  }

  bool network_ok(std::uint32_t net) const { return net >= 1 && net <= cfg_.networks; }

  void execute(const Line& line) {
    const std::uint32_t seq = line.seq;
    if (const auto* h = std::get_if<Help>(&line.command)) {
      out_ += help_text(h->topic);
      return;
    }
    if (const auto* s = std::get_if<SetNetwork>(&line.command)) {
      if (!network_ok(s->net)) return void(out_ += error_response(seq, Error::UnsupportedNet));
      defaults_.net = s->net;
      return void(out_ += ok_response(seq));
    }
    if (!network_ok(line.net)) return void(out_ += error_response(seq, Error::UnsupportedNet));
    std::visit(
        [&](const auto& c) {
          using T = std::decay_t<decltype(c)>;
          if constexpr (std::is_same_v<T, SetNode>) {
            defaults_.node = c.node;
            out_ += ok_response(seq);
          } else if constexpr (std::is_same_v<T, SetSdoTimeout>) {
            defaults_.sdo_timeout_ms = c.ms;
            out_ += ok_response(seq);
          } else if constexpr (std::is_same_v<T, SetSdoBlock>) {
            defaults_.sdo_block = c.on;
            out_ += ok_response(seq);
          } else if constexpr (std::is_same_v<T, SdoReadCmd>) {
            core::SdoRead r;
            r.node = line.node;
            r.index = c.index;
            r.sub = c.sub;
            r.type = canopen::DataType::Domain;  // the bytes; printed here as the datatype asks
            r.timeout = std::chrono::milliseconds(defaults_.sdo_timeout_ms);
            r.block = defaults_.sdo_block;
            run(line.net, r, [seq, type = c.type](Session& s, core::Result res) {
              if (const auto* v = std::get_if<core::SdoValue>(&res)) {
                const auto* bytes = std::get_if<canopen::Bytes>(&v->value.data);
                s.start_stream(seq, type, bytes != nullptr ? *bytes : canopen::encode(v->value));
              } else if (const auto* p = std::get_if<core::Problem>(&res)) {
                s.out_ += problem_text(seq, *p);
              } else {
                s.out_ += error_response(seq, Error::InternalState);
              }
            });
          } else if constexpr (std::is_same_v<T, SdoWriteCmd>) {
            core::SdoWrite w;
            w.node = line.node;
            w.index = c.index;
            w.sub = c.sub;
            w.value = core_value(c.type, c.data);
            w.type = std::get<canopen::Value>(w.value).type;
            w.timeout = std::chrono::milliseconds(defaults_.sdo_timeout_ms);
            w.block = defaults_.sdo_block;
            run(line.net, std::move(w), [seq](Session& s, core::Result res) { s.out_ += ok_or_problem(seq, res); });
          } else if constexpr (std::is_same_v<T, NmtCmd>) {
            run(line.net, core::Nmt{line.node, c.command},
                [seq](Session& s, core::Result res) { s.out_ += ok_or_problem(seq, res); });
          } else if constexpr (std::is_same_v<T, LssCommand>) {
            lss(line.net, seq, c);
          } else {
            out_ += error_response(seq, Error::RequestNotSupported);
          }
        },
        line.command);
  }

  static std::string ok_or_problem(std::uint32_t seq, const core::Result& res) {
    if (const auto* p = std::get_if<core::Problem>(&res)) return problem_text(seq, *p);
    return ok_response(seq);
  }

  // Hands one command to the request core; `finish` runs on the io thread
  // afterwards (never inside execute(), so a refusal does not recurse),
  // unless the connection is gone by then.
  template <typename Finish>
  void run(std::uint32_t net, core::Command command, Finish finish) {
    auto srv = srv_.lock();
    if (!srv) return;
    busy_ = true;
    core::Request req;
    req.caller = caller_;
    req.network = net;
    req.command = std::move(command);
    std::weak_ptr<Session> weak = shared_from_this();
    auto& io = srv->io;
    srv->core.execute(std::move(req), [weak, finish, &io](core::Result res) {
      asio::post(io, [weak, finish, res = std::move(res)]() mutable {
        auto self = weak.lock();
        if (!self || self->closed_) return;
        self->busy_ = false;
        self->touch();
        finish(*self, std::move(res));
        self->process();
      });
    });
  }

  void lss(std::uint32_t net, std::uint32_t seq, const LssCommand& command) {
    auto srv = srv_.lock();
    if (!srv || !srv->lss) return void(out_ += error_response(seq, Error::RequestNotSupported));
    busy_ = true;
    std::weak_ptr<Session> weak = shared_from_this();
    auto answered = std::make_shared<bool>(false);
    auto& io = srv->io;
    srv->lss(LssRequest{net, seq, caller_, command}, [weak, answered, &io](std::string text) {
      if (*answered) return;  // exactly one answer per command
      *answered = true;
      asio::post(io, [weak, text = std::move(text)]() mutable {
        auto self = weak.lock();
        if (!self || self->closed_) return;
        self->busy_ = false;
        self->touch();
        self->out_ += text;
        self->process();
      });
    });
  }

  // A value read: "[seq] " and then its text piece by piece, as the client
  // takes it (pump()), so a large domain never sits here as a whole text.
  void start_stream(std::uint32_t seq, Datatype type, canopen::Bytes data) {
    out_ += "[" + std::to_string(seq) + "] ";
    const std::size_t total = data.size();
    stream_.emplace(Stream{std::move(data), 0, ValuePrinter(type, total)});
    pump();
  }

  void pump() {
    while (stream_ && buffered() < cfg_.max_output) {
      auto& s = *stream_;
      const std::size_t n = std::min(kPrintChunk, s.data.size() - s.pos);
      const bool last = s.pos + n == s.data.size();
      s.printer.print(std::span<const std::uint8_t>(s.data.data() + s.pos, n), last, out_);
      s.pos += n;
      if (last) {
        out_ += "\r\n";
        stream_.reset();
      }
    }
  }

  void flush() {
    if (writing_ || out_.empty() || closed_) return;
    writing_ = true;
    const std::size_t n = std::min(out_.size(), kWriteChunk);
    wbuf_.assign(out_, 0, n);
    out_.erase(0, n);
    asio::async_write(sock_, asio::buffer(wbuf_),
                      [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
                        self->writing_ = false;
                        if (self->closed_) return;
                        if (ec) return self->close();
                        self->touch();
                        self->pump();
                        self->process();
                      });
  }

  void maybe_close() {
    if (input_done_ && !busy_ && !stream_ && pending_.empty() && out_.empty() && !writing_) close();
  }

  struct Stream {
    canopen::Bytes data;
    std::size_t pos = 0;
    ValuePrinter printer;
  };

  std::weak_ptr<Server::Impl> srv_;
  Protocol::socket sock_;
  asio::steady_timer timer_;
  LineFramer framer_;
  const ServerConfig cfg_;
  core::Caller caller_;
  Defaults defaults_;
  std::uint32_t last_seq_ = 0;  // CANopenNode answers a line without one with the previous one
  std::deque<LineFramer::Item> pending_;
  std::optional<Stream> stream_;
  std::array<char, 4096> rbuf_{};
  std::string out_;   // answers not yet handed to the socket
  std::string wbuf_;  // the piece being written
  bool reading_ = false, writing_ = false, busy_ = false, input_done_ = false, closed_ = false;
  std::chrono::steady_clock::time_point last_activity_;  // as the idle timer last saw it
  bool touched_ = false;                                  // activity since the idle timer last looked
};

void Server::Impl::accept() {
  if (!acceptor || !running) return;
  acceptor->async_accept([self = shared_from_this()](const boost::system::error_code& ec, Protocol::socket sock) {
    if (!self->running) return;
    if (ec) {
      if (ec == asio::error::operation_aborted) return;
      return self->accept();  // EMFILE and the like: keep serving the others
    }
    const std::uint64_t id = self->next_id++;
    std::string peer;
    if (self->listen.unix_socket) {
      peer = "unix#" + std::to_string(id);
    } else {
      boost::system::error_code e2;
      const auto ep = sock.remote_endpoint(e2);
      if (!e2 && ep.protocol().family() != AF_UNIX) {
        const auto tcp = tcp_endpoint(ep);
        peer = (tcp.address().is_v6() ? "[" + tcp.address().to_string() + "]" : tcp.address().to_string()) + ":" +
               std::to_string(tcp.port());
      } else {
        peer = "#" + std::to_string(id);
      }
    }
    if (self->sessions.size() >= self->cfg.max_clients) {
      if (self->log) self->log->warn("ascii: " + peer + " refused: " + std::to_string(self->cfg.max_clients) +
                                     " clients connected already (ascii.max-clients)");
      boost::system::error_code e3;
      sock.close(e3);
      return self->accept();
    }
    auto s = std::make_shared<Session>(self, std::move(sock), peer, id, self->cfg);
    self->sessions.push_back(s);
    if (self->log) self->log->debug("ascii: client " + peer + " connected");
    s->start();
    self->accept();
  });
}

void Server::Impl::remove(const std::shared_ptr<Session>& s) {
  sessions.remove(s);
}

// ---- the server ----------------------------------------------------------------------

Server::Server(asio::io_context& io, ServerConfig config, core::RequestCore& core, Logger* log)
    : impl_(std::make_shared<Impl>(io, std::move(config), core, log)) {}

Server::~Server() { stop(); }

void Server::start() {
  auto l = parse_listen(impl_->cfg.listen);
  if (!l) throw std::invalid_argument("'" + impl_->cfg.listen + "' is not ADDR:PORT or unix:/path");
  impl_->listen = *l;
  Protocol::endpoint ep;
  if (l->unix_socket) {
    std::error_code ec;
    // A socket left by an earlier run is replaced; anything else at the path is not.
    if (std::filesystem::is_socket(l->path, ec)) std::filesystem::remove(l->path, ec);
    ep = Protocol::endpoint(asio::local::stream_protocol::endpoint(l->path));
  } else {
    ep = Protocol::endpoint(l->tcp);
  }
  asio::basic_socket_acceptor<Protocol> acc(impl_->io);
  acc.open(ep.protocol());
  if (!l->unix_socket) acc.set_option(asio::socket_base::reuse_address(true));
  acc.bind(ep);
  if (l->unix_socket && ::chmod(l->path.c_str(), 0660) != 0)
    throw std::system_error(errno, std::generic_category(), "chmod " + l->path);
  acc.listen();
  if (!l->unix_socket) {
    impl_->port = tcp_endpoint(acc.local_endpoint()).port();
  }
  impl_->acceptor.emplace(std::move(acc));
  impl_->running = true;
  impl_->accept();
}

void Server::stop() {
  if (!impl_->running) return;
  impl_->running = false;
  boost::system::error_code ec;
  if (impl_->acceptor) impl_->acceptor->close(ec);
  impl_->acceptor.reset();
  auto sessions = impl_->sessions;  // close() removes itself
  for (auto& s : sessions) s->close();
  impl_->sessions.clear();
  if (impl_->listen.unix_socket) {
    std::error_code e2;
    std::filesystem::remove(impl_->listen.path, e2);
  }
}

void Server::set_lss_handler(LssHandler handler) { impl_->lss = std::move(handler); }

std::string Server::local_address() const {
  if (impl_->listen.unix_socket) return "unix:" + impl_->listen.path;
  const auto a = impl_->listen.tcp.address();
  return (a.is_v6() ? "[" + a.to_string() + "]" : a.to_string()) + ":" + std::to_string(impl_->port);
}

std::uint16_t Server::bound_port() const { return impl_->port; }

std::size_t Server::clients() const { return impl_->sessions.size(); }

std::size_t Server::buffered_output() const {
  std::size_t n = 0;
  for (const auto& s : impl_->sessions) n = std::max(n, s->buffered());
  return n;
}

}  // namespace gateway::ascii
