// sdo_tool: the SDO server and client of the stack over real SocketCAN, for
// the system tests (two processes on one vcan bus).
//
//   sdo_tool serve IFACE NODE
//       serves the gateway dictionary of NODE plus test objects:
//       2000h DOMAIN rw (1 MiB pattern), 2001h VISIBLE_STRING rw, 2002h UNSIGNED32 rw
//   sdo_tool upload IFACE NODE INDEX SUB [--mode M] [--out FILE] [--timeout MS] [--repeat N]
//   sdo_tool download IFACE NODE INDEX SUB (--hex HEX | --file FILE) [--mode M] [--timeout MS]
//       M: auto (default), expedited, segmented, block
//       prints "ok SIZE crc XXXX" (CRC-16 of CiA 301 7.2.4.3.16 over the data),
//       for uploads without --out also "data HEX"; on failure prints
//       "abort XXXXXXXX (remote|local): text" and exits 1.
//       --repeat N: N more uploads one after the other (bench/sdo_latency.sh:
//       the round trip without any front end), then one line
//       "latency n=N mean=M ms p50=.. p90=.. p99=.. max=.." over those N.
#include <boost/asio/io_context.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/signal_set.hpp>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <numeric>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "canopen/od/gateway_dictionary.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/sdo/server.hpp"
#include "canopen/socketcan/channel.hpp"
#include "canopen/socketcan/service_driver.hpp"
#include "tool_support.hpp"

namespace {

using canopen::Bytes;

using canopen::tools::parse_number;

Bytes from_hex(const std::string& hex) {
  if (hex.size() % 2 != 0) throw std::invalid_argument("odd number of hex digits");
  Bytes b;
  for (std::size_t i = 0; i < hex.size(); i += 2) {
    b.push_back(static_cast<std::uint8_t>(std::stoul(hex.substr(i, 2), nullptr, 16)));
  }
  return b;
}

std::string to_hex(const Bytes& b) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (auto x : b) {
    s.push_back(digits[x >> 4]);
    s.push_back(digits[x & 15]);
  }
  return s;
}

canopen::sdo::Mode parse_mode(const std::string& m) {
  if (m == "auto") return canopen::sdo::Mode::Auto;
  if (m == "expedited") return canopen::sdo::Mode::Expedited;
  if (m == "segmented") return canopen::sdo::Mode::Segmented;
  if (m == "block") return canopen::sdo::Mode::Block;
  throw std::invalid_argument("unknown mode '" + m + "'");
}

Bytes test_pattern(std::size_t n) {
  Bytes b(n);
  std::uint32_t x = 0x12345678;
  for (auto& v : b) {
    x = x * 1664525U + 1013904223U;  // deterministic, not compressible-looking
    v = static_cast<std::uint8_t>(x >> 24);
  }
  return b;
}

struct Bus {
  boost::asio::io_context io;
  std::shared_ptr<canopen::socketcan::LinkMonitor> monitor = canopen::socketcan::LinkMonitor::create(io);
  std::shared_ptr<canopen::socketcan::SocketCanChannel> channel;
  explicit Bus(const std::string& iface) {
    canopen::socketcan::ChannelOptions opts;
    opts.tx_queue_capacity = 1 << 16;  // a whole block upload sub-block may be queued at once
    channel = canopen::socketcan::SocketCanChannel::open(io, iface, monitor, opts);
  }
  void stop() {
    channel->close();
    monitor->stop();
  }
  canopen::sdo::FrameSink sink() {
    return [this](const canopen::can::Frame& f) { channel->send(f); };
  }
};

int serve(const std::string& iface, std::uint8_t node) {
  Bus bus(iface);
  auto od = canopen::od::make_gateway_dictionary(node, {});
  using canopen::DataType;
  using canopen::od::Access;
  od.insert(canopen::od::make_var(0x2000, "test domain", DataType::Domain, Access::ReadWrite,
                                  canopen::Value::of_bytes(DataType::Domain, test_pattern(1 << 20))));
  od.insert(canopen::od::make_var(0x2001, "test string", DataType::VisibleString, Access::ReadWrite,
                                  canopen::Value::of_string("canopen-gateway sdo_tool")));
  od.insert(canopen::od::make_var(0x2002, "test u32", DataType::Unsigned32, Access::ReadWrite,
                                  canopen::Value::of_unsigned(DataType::Unsigned32, 0xCAFE)));
  canopen::sdo::ServerConfig cfg;
  cfg.node_id = node;
  cfg.max_download_size = 4 << 20;
  canopen::sdo::SdoServer server(od, cfg, bus.sink());
  canopen::socketcan::ServiceDriver driver(bus.io, *bus.channel);
  driver.add(server);
  boost::asio::signal_set signals(bus.io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) {
    driver.remove(&server);
    bus.stop();
  });
  std::printf("ready\n");
  std::fflush(stdout);
  bus.io.run();
  return 0;
}

int transfer(bool upload, const std::vector<std::string>& a) {
  const std::string iface = a[1];
  const auto node = static_cast<std::uint8_t>(parse_number(a[2]));
  canopen::sdo::Request req;
  req.node = node;
  req.index = static_cast<std::uint16_t>(parse_number(a[3]));
  req.sub = static_cast<std::uint8_t>(parse_number(a[4]));
  std::string out_file;
  Bytes data;
  std::size_t repeat = 0;
  for (std::size_t i = 5; i + 1 < a.size(); i += 2) {
    if (a[i] == "--mode") req.mode = parse_mode(a[i + 1]);
    else if (a[i] == "--repeat" && upload) repeat = static_cast<std::size_t>(parse_number(a[i + 1]));
    else if (a[i] == "--out") out_file = a[i + 1];
    else if (a[i] == "--timeout") req.timeout = std::chrono::milliseconds(parse_number(a[i + 1]));
    else if (a[i] == "--hex") data = from_hex(a[i + 1]);
    else if (a[i] == "--file") {
      std::ifstream in(a[i + 1], std::ios::binary);
      data.assign(std::istreambuf_iterator<char>(in), {});
    } else throw std::invalid_argument("unknown option " + a[i]);
  }
  Bus bus(iface);
  canopen::sdo::SdoClient client({}, bus.sink());
  canopen::socketcan::ServiceDriver driver(bus.io, *bus.channel);
  driver.add(client);
  int rc = 1;
  // The download data is moved into the client: summarise it first.
  const std::size_t down_size = data.size();
  const std::uint16_t down_crc = canopen::sdo::crc16(data);
  const canopen::sdo::Request again = req;
  std::vector<double> ms;
  canopen::TimePoint started{};
  std::function<void(canopen::sdo::TransferResult&&)> done;
  done = [&](canopen::sdo::TransferResult&& r) {
    if (r.ok() && ms.size() < repeat) {
      const auto t = canopen::SteadyClock::now();
      // The first (the one printed below) is not counted: it warms up.
      if (started != canopen::TimePoint{}) ms.push_back(std::chrono::duration<double, std::milli>(t - started).count());
      started = t;
      canopen::sdo::Request next = again;
      next.on_done = done;
      if (client.upload(std::move(next), started)) return;
      std::fprintf(stderr, "sdo_tool: the next upload was refused\n");
      r.error = make_error_code(canopen::SdoAbort::GeneralError);
    }
    if (!ms.empty()) {
      std::sort(ms.begin(), ms.end());
      const auto pick = [&](double q) {
        return ms[std::min(ms.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ms.size())))];
      };
      std::printf("latency n=%zu mean=%.3f ms p50=%.3f p90=%.3f p99=%.3f max=%.3f\n", ms.size(),
                  std::accumulate(ms.begin(), ms.end(), 0.0) / static_cast<double>(ms.size()), pick(0.5), pick(0.9),
                  pick(0.99), ms.back());
    }
    if (r.ok()) {
      if (upload) std::printf("ok %zu crc %04x\n", r.data.size(), canopen::sdo::crc16(r.data));
      else std::printf("ok %zu crc %04x\n", down_size, down_crc);
      if (upload && !out_file.empty()) {
        std::ofstream(out_file, std::ios::binary)
            .write(reinterpret_cast<const char*>(r.data.data()), static_cast<std::streamsize>(r.data.size()));
      } else if (upload) {
        std::printf("data %s\n", to_hex(r.data).c_str());
      }
      rc = 0;
    } else {
      std::printf("abort %08x (%s): %s%s%s\n", canopen::to_abort_code(r.error),
                  r.origin == canopen::sdo::Origin::Remote ? "remote" : "local", r.error.message().c_str(),
                  r.detail.empty() ? "" : " - ", r.detail.c_str());
    }
    boost::asio::post(bus.io, [&] {
      driver.remove(&client);
      bus.stop();
    });
  };
  req.on_done = done;
  const auto now = canopen::SteadyClock::now();
  auto id = upload ? client.upload(std::move(req), now) : client.download(std::move(req), std::move(data), now);
  if (!id) {
    std::fprintf(stderr, "sdo_tool: %s %s\n", id.error().code.message().c_str(), id.error().detail.c_str());
    return 2;
  }
  bus.io.run();
  std::fflush(stdout);
  return rc;
}

int usage() {
  std::fputs("usage: sdo_tool serve IFACE NODE | upload IFACE NODE INDEX SUB [opts] | download ... (see source)\n",
             stderr);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> a(argv + 1, argv + argc);
  try {
    if (a.size() == 3 && a[0] == "serve") return serve(a[1], static_cast<std::uint8_t>(parse_number(a[2])));
    if (a.size() >= 5 && (a[0] == "upload" || a[0] == "download")) return transfer(a[0] == "upload", a);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sdo_tool: %s\n", e.what());
    return 2;
  }
  return usage();
}
