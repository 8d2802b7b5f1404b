// NMT master (CiA 301 7.2.8): node control commands, tracking of every node
// heard on the error control COB-IDs (boot-up, heartbeat), heartbeat
// consumer (1016h) and node guarding master (7.2.8.3.2.1).
//
// Sans-I/O: the caller feeds received frames and the current time; the
// master emits frames through the sink and events through the event sink.
// The caller MUST
//   - pass every received frame to on_frame() (only 701h..77Fh are used);
//   - call on_time(now) when now >= next_deadline() (consumer timeouts,
//     guarding requests, node life time expiry).
// The set_*() and configure_consumers() calls report the new deadline to
// the on_deadline_change() observer (canopen/deadline.hpp).
//
// Behaviour, as chosen here where the standard leaves room:
//   - Events carry the receive timestamp of the frame that caused them;
//     Lost events have no causing frame and carry Frame::Clock::time_point{}
//     (the network stamps them with its own wall clock).
//   - A boot-up message (00h) means the node is now pre-operational: the
//     event is NodeStateEvent{cause BootUp, state PreOperational}. It also
//     counts as the node's first heartbeat, clears a Lost condition and
//     expects the next guarding toggle to be 0 (the node reset communication).
//   - A heartbeat consumer starts monitoring with the first heartbeat (or
//     boot-up) received after it is configured; the node is Lost when no
//     heartbeat arrived for exactly the consumer time (at last + T, not
//     before). After Lost, the next heartbeat gives Recovered.
//   - Watching without a configured consumer time (the contract's "node
//     monitoring without configuration", on for every node by default): a
//     node heard that has neither a heartbeat consumer nor node guarding is
//     Lost when no heartbeat or boot-up came for 3 x P (at last + 3P, not
//     before). P is the period given with set_auto_watch() (the node's
//     1017h from its EDS/DCF, or the 1017h written to it: set_producer_time()),
//     else learnt: the longest of the last 8 intervals between consecutive
//     heartbeats, so P follows a node that slows down at once and one that
//     speeds up within 8 heartbeats. A given P is a floor: a producer that
//     is slower than it (another tool wrote its 1017h) is followed the same
//     way (7.5.2.19: the consumer time must exceed the producer time). A
//     learnt P needs two heartbeats; a boot-up counts as a heartbeat for
//     the deadline but starts no interval. After Lost the interval history
//     is dropped (the node may come back with another 1017h). A producer
//     slower than 3P is Lost before each of its heartbeats: when two
//     recoveries in a row end gaps of the same length (within 1/8, at most
//     10 x P) with no heartbeat between, that gap is taken as an interval,
//     so such a producer is followed after two Lost/Recovered, while a node
//     that was away once does not stretch P. set_auto_watch(node, false)
//     turns it off.
//   - Node guarding: the first request goes out when guarding is set up,
//     then one every guard time. A response whose toggle bit equals the
//     previous accepted one is ignored and counted in toggle_errors
//     (7.2.8.3.2.1). No accepted response for guard time x life time factor
//     -> Lost; requests continue so a later response gives Recovered.
//   - A data frame on 700h + node while a guarding request to that node is
//     outstanding is its guarding response; otherwise it is a heartbeat.
//
// Thread safety: none; use from one thread. Sinks are called synchronously
// and must not call back into the master.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/deadline.hpp"
#include "canopen/events.hpp"
#include "canopen/nmt/nmt.hpp"
#include "canopen/od/object_dictionary.hpp"

namespace canopen::nmt {

// Receives NodeStateEvent and HeartbeatEvent bodies with the timestamp of
// the causing frame.
using EventSink = std::function<void(const EventBody& body, can::Frame::Clock::time_point timestamp)>;

// What the master knows about one node.
struct NodeStatus {
  std::optional<NmtState> state;     // last reported (PreOperational after a boot-up)
  std::optional<TimePoint> last_seen;  // last boot-up, heartbeat or accepted guarding response
  std::uint32_t boot_ups = 0;
  std::uint64_t heartbeats = 0;
  std::uint32_t toggle_errors = 0;   // guarding responses ignored for a repeated toggle bit
  bool lost = false;
};

// A node's producer heartbeat time (1017h) from its EDS/DCF description (the
// DCF's ParameterValue, else the DefaultValue): the period to give
// NmtMaster::set_auto_watch(). Zero when the description has none or 0.
Duration producer_heartbeat_time(const od::ObjectDictionary& description);

class NmtMaster : public DeadlineSource {
 public:
  NmtMaster(FrameSink sink, EventSink events);

  // Sends a node control command to `node` (1..127) or to all nodes (0).
  // Returns false (nothing sent) for node-IDs above 127.
  bool send_command(NmtCommand cs, std::uint8_t node);

  bool on_frame(const can::Frame& frame, TimePoint now);
  // TimePoint::max() when nothing is monitored.
  TimePoint next_deadline() const;
  void on_time(TimePoint now);

  // Heartbeat consumer for one node (1..127); time 0 removes it. Changing
  // the time restarts monitoring from the next heartbeat.
  bool set_heartbeat_consumer(std::uint8_t node, Duration time);
  // Replaces every consumer with the used entries of 1016h (bits 16..23
  // node-ID, bits 0..15 time in ms; entries with time 0 or node-ID 0 / >127
  // are unused). Call again after 1016h changes.
  void configure_consumers(const od::ObjectDictionary& dictionary);

  // Watching of `node` (1..127) while it has no heartbeat consumer and no
  // node guarding (see above): enabled with `period` as P (0: learn it from
  // the node's heartbeats), or off. Every node is watched with a learnt P
  // unless this says otherwise. Returns false for an invalid node-ID.
  bool set_auto_watch(std::uint8_t node, bool enabled, Duration period = Duration::zero());
  // The node's producer heartbeat time (1017h) was set by this side (an SDO
  // download the caller made): when the node is auto-watched, P is `time`
  // from now on (deadline now + 3 x time, the learnt intervals dropped);
  // zero: it sends no heartbeat any more, so it is not expected until it
  // is heard again (P learnt anew). No effect on an explicit consumer or
  // guarding. Reports the deadline change. False for an invalid node-ID.
  bool set_producer_time(std::uint8_t node, Duration time, TimePoint now);
  // The P watching uses for `node` now; zero when not known (yet) or not watched.
  Duration auto_watch_period(std::uint8_t node) const;

  // Node guarding for one node: a request every guard_time, Lost after
  // guard_time x life_time_factor without a response. Either 0 removes it.
  bool set_node_guarding(std::uint8_t node, Duration guard_time, std::uint8_t life_time_factor, TimePoint now);

  // nullptr for a node never heard of.
  const NodeStatus* node(std::uint8_t id) const;
  const std::map<std::uint8_t, NodeStatus>& nodes() const { return nodes_; }

 private:
  struct Consumer {
    Duration time{};
    TimePoint deadline = TimePoint::max();  // max: waiting for the first heartbeat
  };
  static constexpr std::size_t kLearnWindow = 8;
  struct AutoWatch {
    bool enabled = true;
    Duration period{};  // given; zero: learnt from `intervals`
    std::array<Duration, kLearnWindow> intervals{};
    std::size_t count = 0, next = 0;          // ring of the latest intervals
    std::optional<TimePoint> last_heartbeat;  // start of the next interval
    Duration recovered_gap{};                 // the gap the latest heartbeat ended, when it ended a Lost
    TimePoint deadline = TimePoint::max();
    Duration p() const;
  };
  struct Guarding {
    Duration guard_time{};
    std::uint8_t life_factor = 0;
    TimePoint next_request = TimePoint::max();
    TimePoint life_deadline = TimePoint::max();
    bool awaiting = false;     // a request is outstanding
    bool last_toggle = true;   // so that the first accepted response has toggle 0
  };

  void on_boot_up(std::uint8_t node, const can::Frame& f, TimePoint now);
  void on_heartbeat(std::uint8_t node, NmtState s, const can::Frame& f, TimePoint now);
  void on_guard_response(std::uint8_t node, Guarding& g, std::uint8_t byte, const can::Frame& f, TimePoint now);
  // Updates the state and emits Recovered or a state change with `cause`.
  void report_state(std::uint8_t node, NmtState s, NodeStateEvent::Cause cause, const can::Frame& f);
  void lose(std::uint8_t node);
  // A heartbeat (or boot-up) of `node` for auto watching; was_lost: the
  // node was Lost until this frame.
  void auto_heard(std::uint8_t node, TimePoint now, bool boot_up, bool was_lost);
  bool has_explicit_watch(std::uint8_t node) const { return consumers_.contains(node) || guarding_.contains(node); }
  void emit(const EventBody& body, can::Frame::Clock::time_point ts);

  FrameSink sink_;
  EventSink events_;
  std::map<std::uint8_t, NodeStatus> nodes_;
  std::map<std::uint8_t, Consumer> consumers_;
  std::map<std::uint8_t, Guarding> guarding_;
  std::map<std::uint8_t, AutoWatch> auto_;
};

}  // namespace canopen::nmt
