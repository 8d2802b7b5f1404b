// A CANopen device (the slave side of CiA 301) as one sans-I/O unit on an
// object dictionary: NMT slave (boot-up, heartbeat, guarding), SDO server,
// EMCY producer, SYNC consumer (and producer when 1005h bit 30 says so),
// TIME consumer/producer (1012h bits 31/30), and the device's own PDOs:
// TPDOs from 1800h-19FFh/1A00h-1BFFh and RPDOs from 1400h-15FFh/1600h-17FFh.
//
// Used for simulated remote nodes and for the gateway's own node alike.
//
// The caller MUST
//   - keep the dictionary alive as long as the Device and the Device at one
//     address (services hold pointers to it; dictionary observers installed
//     here hold a token the destructor disarms, so a dictionary may outlive
//     its Device);
//   - call start(now) once (power-on: boot-up message, pre-operational);
//   - pass every received frame to on_frame() (other nodes' frames are
//     ignored, so the whole bus is fine) and call on_time(now) whenever
//     now >= next_deadline(), re-reading it after its own on_frame() and
//     on_time() calls.
// Every other change of the deadline - start(), set(), command(),
// raise_emcy(), clear_emcy(), reconfigure_pdos(), on_frame() from outside
// a driver, a direct write of the dictionary (then TimePoint::min()) - is
// reported to the on_deadline_change() observer (canopen/deadline.hpp)
// when the call returns. Changes made through the nmt() and emcy()
// accessors are not: use the Device's own methods.
//
// Behaviour (CiA 301 sections in brackets):
//   - Services by NMT state (7.3.2.2.5, table 37): PDOs only in
//     operational, SDO/SYNC/TIME/EMCY in pre-operational and operational,
//     only NMT and error control in stopped. Frames a service produces in a
//     state where it is not allowed are dropped.
//   - TPDOs (7.2.2): every write of a mapped object - SDO download, RPDO,
//     set(), or ObjectDictionary::set() by the application - is an event for
//     each TPDO mapping it; the transmission type decides what happens
//     (pdo/transmitter.hpp). Synchronous TPDOs are driven by received (or
//     produced) SYNCs and not sent outside the synchronous window (1007h).
//   - RPDOs (7.2.2): a received frame is decoded with the mapping and each
//     mapped object set in the dictionary (ObjectDictionary::set: no access
//     or limit check, no write hooks; observers run). A frame shorter than
//     the mapping is ignored and EMCY 8210h is raised; a longer one is used
//     (the mapped bytes) and EMCY 8220h is raised (7.5.2.36). Both are
//     cleared by the next RPDO of correct length. Synchronous RPDOs
//     (type 0-240) received inside the window are applied at the next SYNC.
//   - RPDO deadline monitoring (7.5.2.35, 1400h sub 5 event timer): armed by
//     the first reception in operational; when no RPDO comes within the
//     time, EMCY 8250h is raised (once) and on_rpdo_timeout called; the next
//     reception clears it.
//   - Reconfiguration: a write to 1400h-1BFFh rebuilds the PDOs (also after
//     reset communication); PDOs that cannot be used are listed in
//     pdo_errors() and stay off. Writes to 1005h/1006h/1019h reconfigure
//     the SYNC producer.
//   - Power-on values (7.3.2.2.1): the first start() takes the values of
//     every writable entry of 1000h-9FFFh as the power-on values (not
//     1003h, 1010h, 1011h: history and commands, not parameters; not
//     1F50h-1F5Fh: a downloaded program (CiA 302-3) survives resets). Reset
//     communication sets 1000h-1FFFh back to them, reset node also
//     2000h-9FFFh, before the reset callbacks run; so a 1017h written since
//     is undone and the heartbeat producer, SYNC producer and PDOs follow.
//     store_parameters() (1010h "save") makes the current values the
//     power-on values, restore_default_parameters() (1011h "load") makes
//     the values of the first start() the power-on values again; both
//     take effect at the next reset (7.5.2.13, 7.5.2.14). Nothing is kept
//     beyond the Device's life: a new Device is a power-on.
//
// Thread safety: none; use from one thread. Callbacks run synchronously
// inside the Device's methods and must not call back into the Device except
// through set() (which is safe from on_rpdo and on_state_change).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/deadline.hpp"
#include "canopen/emcy/emcy.hpp"
#include "canopen/sync/sync.hpp"
#include "canopen/time/time.hpp"
#include "canopen/events.hpp"
#include "canopen/nmt/slave.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/pdo/transmitter.hpp"
#include "canopen/sdo/server.hpp"

namespace canopen {

// EMCY codes the Device raises itself.
inline constexpr std::uint16_t kEmcyPdoLength = 0x8210;          // PDO not processed due to length error
inline constexpr std::uint16_t kEmcyPdoLengthExceeded = 0x8220;  // PDO length exceeded
inline constexpr std::uint16_t kEmcyRpdoTimeout = 0x8250;        // RPDO timeout

struct DeviceConfig {
  std::uint8_t node_id = 1;  // 1..127
  // SDO server channel; node_id is overwritten with the one above.
  sdo::ServerConfig sdo{};
  // TIME producer period (only when 1012h bit 30 is set); 0 = no periodic
  // TIME. unix_ms gives the wall time to send (the Device reads no clock).
  Duration time_period{};
  std::function<std::int64_t()> unix_ms = nullptr;
};

struct DeviceCallbacks {
  // After each state change among pre-operational, operational, stopped.
  std::function<void(NmtState now, NmtState before)> on_state_change = nullptr;
  // Every NMT node control command addressed to this node (or all nodes),
  // before it is executed.
  std::function<void(NmtCommand)> on_nmt_command = nullptr;
  // Reset sub-states (nmt/slave.hpp), after the Device has set the area to
  // its power-on values: restore anything else the application keeps.
  std::function<void()> on_reset_application = nullptr;
  std::function<void()> on_reset_communication = nullptr;
  // An RPDO was written into the dictionary: its number and the values (the
  // span is valid during the call only).
  std::function<void(std::uint16_t number, std::span<const MappedValue> values)> on_rpdo = nullptr;
  std::function<void(std::uint16_t number)> on_rpdo_timeout = nullptr;
  std::function<void(const SyncEvent&)> on_sync = nullptr;
  std::function<void(const TimeEvent&)> on_time_of_day = nullptr;
  std::function<void(nmt::LifeGuardingEvent)> on_life_guarding = nullptr;
};

class Device : public DeadlineSource {
 public:
  using FrameSink = std::function<void(const can::Frame&)>;

  Device(od::ObjectDictionary& dictionary, DeviceConfig config, FrameSink sink, DeviceCallbacks callbacks = {});
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // Power-on: initialisation, boot-up message, pre-operational.
  void start(TimePoint now);
  // Returns true when the frame was for one of the device's services.
  bool on_frame(const can::Frame& frame, TimePoint now);
  void on_time(TimePoint now);
  TimePoint next_deadline() const;

  // ---- application side ----------------------------------------------------
  // Sets an object (ObjectDictionary::set rules) and runs the TPDO events it
  // causes at `now`.
  std::error_code set(std::uint16_t index, std::uint8_t sub, Value value, TimePoint now);
  // Local NMT control (7.3.2.3), as if the command had been received.
  void command(NmtCommand cs, TimePoint now);
  // EmcyProducer::raise/clear (7.2.7); frames only leave in pre-operational
  // and operational.
  bool raise_emcy(std::uint16_t code, std::uint8_t register_bits, TimePoint now,
                  const emcy::ManufacturerField& manufacturer = {});
  bool clear_emcy(std::uint16_t code, TimePoint now);
  // Sends TIME now (1012h bit 30 must be set, start() called); false otherwise.
  bool send_time(std::int64_t unix_ms);
  // Rebuilds all PDOs from the dictionary (done automatically on writes to
  // 1400h-1BFFh and on reset communication).
  void reconfigure_pdos(TimePoint now);
  // Parameter groups as the sub-indexes of 1010h/1011h: 1 all, 2
  // communication (1000h-1FFFh), 3 application (2000h-9FFFh), 4
  // manufacturer-specific (2000h-5FFFh; sub 4..7Fh are the manufacturer's
  // choice in CiA 301, this is ours). A 1010h/1011h
  // write hook may call them (they do not touch the dictionary).
  // NoSuchSubIndex for another group, CannotStoreDeviceState before start().
  std::error_code store_parameters(std::uint8_t group);
  std::error_code restore_default_parameters(std::uint8_t group);

  NmtState state() const { return slave_.nmt_state(); }
  std::uint8_t node_id() const { return cfg_.node_id; }
  od::ObjectDictionary& dictionary() { return od_; }
  const std::vector<std::string>& pdo_errors() const { return pdo_errors_; }
  std::vector<std::uint16_t> tpdo_numbers() const;
  std::vector<std::uint16_t> rpdo_numbers() const;
  nmt::NmtSlave& nmt() { return slave_; }
  emcy::EmcyProducer& emcy() { return emcy_; }
  const sdo::SdoServer& sdo() const { return sdo_; }

 private:
  struct Rpdo {
    pdo::PdoConfig cfg;
    std::vector<std::size_t> offsets;  // bit offset of each entry
    std::vector<MappedValue> values;   // reused per frame; dummies skipped
    std::array<std::uint8_t, can::kMaxFdLength> pending{};  // synchronous: data waiting for SYNC
    bool has_pending = false;
    Duration deadline_period{};
    TimePoint deadline = TimePoint::max();
    bool timed_out = false;
    bool length_error = false;
  };
  struct Tpdo {
    std::uint16_t number = 0;
    std::uint32_t can_id = 0;
    bool extended = false;
    bool synchronous = false;
    std::vector<std::pair<std::uint16_t, std::uint8_t>> mapped;
  };
  struct Token {
    Device* device;
  };
  using Parameters = std::map<std::pair<std::uint16_t, std::uint8_t>, Value>;

  void install_observers();
  Parameters parameters(std::uint16_t first, std::uint16_t last) const;
  void restore_power_on(std::uint16_t first, std::uint16_t last);
  void observed(std::uint16_t index, std::uint8_t sub);
  void observed_in_call(std::uint16_t index, std::uint8_t sub);
  struct Outermost;
  void settle(TimePoint now);
  void rebuild_pdos(TimePoint now);
  void handle_rpdo(Rpdo& r, const can::Frame& f, TimePoint now);
  void apply_rpdo(Rpdo& r, std::span<const std::uint8_t> data);
  void update_length_emcy(TimePoint now);
  void update_timeout_emcy(TimePoint now);
  void on_sync_received(const SyncEvent& ev);
  void on_state(NmtState now_state, NmtState before);
  void send_tpdo(const can::Frame& f);
  void send_if(nmt::Service s, const can::Frame& f);

  od::ObjectDictionary& od_;
  DeviceConfig cfg_;
  FrameSink sink_;
  DeviceCallbacks cb_;
  TimePoint now_{};
  std::shared_ptr<Token> token_;

  nmt::NmtSlave slave_;
  sdo::SdoServer sdo_;
  emcy::EmcyProducer emcy_;
  sync::SyncConsumer sync_;
  sync::SyncProducer sync_producer_;
  time::TimeConsumer time_consumer_;
  std::optional<time::TimeProducer> time_producer_;  // from start()
  pdo::PdoTransmitter tpdo_;

  std::vector<Tpdo> tpdos_;
  std::vector<Rpdo> rpdos_;
  std::vector<std::string> pdo_errors_;
  // 7.3.2.2.1: what reset communication / reset node set the areas to, and
  // the values of the first start() (1011h "load" brings them back).
  Parameters power_on_;
  Parameters defaults_;
  bool started_ = false;
  // Writes of mapped objects seen by the observers, run at settle().
  std::vector<std::pair<std::uint16_t, std::uint8_t>> changed_;
  bool pdo_dirty_ = false;
  bool sync_dirty_ = false;
  bool in_call_ = false;
  int depth_ = 0;  // public calls in progress (Outermost)
};

}  // namespace canopen
