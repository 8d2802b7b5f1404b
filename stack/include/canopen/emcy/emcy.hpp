// Emergency object (CiA 301 7.2.7): the producer for the gateway's own node
// and a consumer that decodes the EMCY frames of remote nodes.
//
// Sans-I/O. Producer: the caller MUST call on_time(now) when
// now >= next_deadline() so EMCYs held back by the inhibit time (1015h) go
// out. Consumer: pass every received frame to on_frame(); frames for other
// COB-IDs are ignored, so handing it the whole bus is fine.
//
// Thread safety: none; use from one thread. Sinks and callbacks are called
// synchronously and must not call back into the object that called them.
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <string>
#include <string_view>

#include "canopen/can/frame.hpp"
#include "canopen/clock.hpp"
#include "canopen/cob_id.hpp"
#include "canopen/events.hpp"
#include "canopen/od/object_dictionary.hpp"

namespace canopen::emcy {

// Where the service emits its frames. Called synchronously from the
// service's methods; it must not call back into the service that called it.
using FrameSink = std::function<void(const can::Frame&)>;


using ManufacturerField = std::array<std::uint8_t, 5>;

// Error register bits (7.5.2.2, 1001h).
namespace error_register {
inline constexpr std::uint8_t kGeneric = 1U << 0;  // set whenever any error is present
inline constexpr std::uint8_t kCurrent = 1U << 1;
inline constexpr std::uint8_t kVoltage = 1U << 2;
inline constexpr std::uint8_t kTemperature = 1U << 3;
inline constexpr std::uint8_t kCommunication = 1U << 4;
inline constexpr std::uint8_t kDeviceProfile = 1U << 5;
inline constexpr std::uint8_t kManufacturer = 1U << 7;
}  // namespace error_register

// Text of an emergency error code: the code's own entry of the standard's
// error code table (e.g. 8110h "CAN overrun (objects lost)") when it has
// one, otherwise the text of its class (e.g. 2310h "Current, CANopen device
// output side"); "Unknown error code class" when no class matches.
std::string_view emcy_description(std::uint16_t error_code);
// The class text only (00xxh .. FFxxh).
std::string_view emcy_class_description(std::uint16_t error_code);

// The 8 data bytes of an EMCY frame (7.2.7.3.1): error code (LE), error
// register, manufacturer-specific error field.
std::array<std::uint8_t, 8> encode_emcy(std::uint16_t error_code, std::uint8_t error_register,
                                        const ManufacturerField& manufacturer);

// EMCY producer of the gateway's own node. Reads 1014h (COB-ID; bit 31 set =
// no EMCY is sent) and 1015h (inhibit time, multiples of 100 us) from the
// dictionary at each send, so SDO writes to them take effect at once, and
// keeps 1001h (error register) and 1003h (error history) up to date.
//
// The set of present errors is kept here, keyed by error code:
//   - raise(): a new error. 1001h becomes the OR of the register bits of all
//     present errors plus the generic bit; 1003h gets the code (with the
//     additional information in its upper 16 bits); an EMCY with the code
//     and the new register is sent. Raising a code already present is one
//     error event that already reported, so nothing happens (7.2.7.1: "an
//     error event triggers the EMCY only once").
//   - clear(): one error is gone. An error reset EMCY (0000h) is sent with
//     the register of the errors still present (7.2.7.1 transitions 3 and
//     5); when none remain the register is 0 and the device is error-free.
// The register byte of each frame is the register at the time of the event,
// even when the frame is held back by the inhibit time.
//
// Inhibit time: after an EMCY is sent, the next one waits until
// 1015h x 100 us have passed. Frames raised meanwhile are queued in order
// and sent one per inhibit period; none are dropped (the queue grows only
// with raise()/clear() calls, which the application controls). While 1014h
// is invalid no frame is sent or queued, but 1001h/1003h are still kept;
// frames still held back when 1014h turns invalid are discarded (they
// would carry the old COB-ID).
class EmcyProducer {
 public:
  // The dictionary must outlive the producer. It needs 1001h and 1014h;
  // 1003h and 1015h are used when present.
  EmcyProducer(od::ObjectDictionary& dictionary, FrameSink sink);

  // Returns false (and does nothing) when `error_code` is already present or
  // is 0000h. `register_bits` are the category bits of 1001h for this error;
  // the generic bit is added.
  bool raise(std::uint16_t error_code, std::uint8_t register_bits, TimePoint now,
             const ManufacturerField& manufacturer = {}, std::uint16_t additional_info = 0);
  // Returns false when `error_code` is not present.
  bool clear(std::uint16_t error_code, TimePoint now, const ManufacturerField& manufacturer = {});
  // Clears every present error with a single error reset EMCY (register 0);
  // no-op when error-free.
  void clear_all(TimePoint now);

  bool has_errors() const { return !present_.empty(); }
  bool is_present(std::uint16_t error_code) const { return present_.contains(error_code); }
  std::uint8_t error_register() const;
  std::size_t queued() const { return queue_.size(); }

  // End of the inhibit time when frames are queued, TimePoint::max() otherwise.
  TimePoint next_deadline() const;
  // Sends the next queued frame when its inhibit time has passed.
  void on_time(TimePoint now);

 private:
  void emit(std::uint16_t error_code, const ManufacturerField& manufacturer, TimePoint now);
  void store_register();
  Duration inhibit() const;
  void transmit(const can::Frame& f, TimePoint now);

  od::ObjectDictionary& od_;
  FrameSink sink_;
  std::map<std::uint16_t, std::uint8_t> present_;  // error code -> register bits
  std::deque<can::Frame> queue_;
  bool sent_any_ = false;
  TimePoint last_sent_{};
};

// COB-IDs of the EMCYs to consume, keyed by node-ID.
struct EmcyConsumerConfig {
  // Node-ID -> COB-ID (bit 29 selects a 29-bit CAN-ID; entries with bit 31
  // set are ignored). Empty: 80h + node-ID for nodes 1..127.
  std::map<std::uint8_t, std::uint32_t> cob_ids;

  // From 1028h (7.5.2.31, sub-index N = node-ID N). The default above when
  // the dictionary has no 1028h.
  static EmcyConsumerConfig from_dictionary(const od::ObjectDictionary& od);
};

// Decodes EMCY frames of remote nodes into EmcyEvents. A frame shorter than
// 8 bytes is still reported, with the bytes it has (missing ones read as 0)
// and a description starting "malformed EMCY".
class EmcyConsumer {
 public:
  using Callback = std::function<void(const EmcyEvent&)>;

  EmcyConsumer(EmcyConsumerConfig config, Callback callback);

  // Returns false when the frame is not an EMCY of a consumed node.
  bool on_frame(const can::Frame& frame, TimePoint now);
  // No timers: TimePoint::max(); on_time() does nothing. Present so a
  // driver can treat all services alike.
  TimePoint next_deadline() const { return TimePoint::max(); }
  void on_time(TimePoint /*now*/) {}

 private:
  std::map<std::uint32_t, std::uint8_t> nodes_;  // COB-ID (with bit 29) -> node-ID
  Callback callback_;
};

}  // namespace canopen::emcy
