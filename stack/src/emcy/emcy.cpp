// EMCY producer and consumer (CiA 301 7.2.7); texts from the error code
// tables of 7.2.7.1 (classes, and the codes the standard names).
#include "canopen/emcy/emcy.hpp"

#include <algorithm>
#include <utility>

#include "canopen/od/gateway_dictionary.hpp"

namespace canopen::emcy {
namespace {

struct CodeText {
  std::uint16_t code;
  std::string_view text;
};

constexpr CodeText kCodes[] = {
    {0x0000, "Error reset or no error"},
    {0x1000, "Generic error"},
    {0x2000, "Current - generic error"},
    {0x2100, "Current, CANopen device input side - generic"},
    {0x2200, "Current inside the CANopen device - generic"},
    {0x2300, "Current, CANopen device output side - generic"},
    {0x3000, "Voltage - generic error"},
    {0x3100, "Mains voltage - generic"},
    {0x3200, "Voltage inside the CANopen device - generic"},
    {0x3300, "Output voltage - generic"},
    {0x4000, "Temperature - generic error"},
    {0x4100, "Ambient temperature - generic"},
    {0x4200, "Device temperature - generic"},
    {0x5000, "CANopen device hardware - generic error"},
    {0x6000, "CANopen device software - generic error"},
    {0x6100, "Internal software - generic"},
    {0x6200, "User software - generic"},
    {0x6300, "Data set - generic"},
    {0x7000, "Additional modules - generic error"},
    {0x8000, "Monitoring - generic error"},
    {0x8100, "Communication - generic"},
    {0x8110, "CAN overrun (objects lost)"},
    {0x8120, "CAN in error passive mode"},
    {0x8130, "Life guard error or heartbeat error"},
    {0x8140, "Recovered from bus off"},
    {0x8150, "CAN-ID collision"},
    {0x8200, "Protocol error - generic"},
    {0x8210, "PDO not processed due to length error"},
    {0x8220, "PDO length exceeded"},
    {0x8230, "DAM MPDO not processed, destination object not available"},
    {0x8240, "Unexpected SYNC data length"},
    {0x8250, "RPDO timeout"},
    {0x9000, "External error - generic error"},
    {0xF000, "Additional functions - generic error"},
    {0xFF00, "Device specific - generic error"},
};

struct ClassText {
  std::uint8_t high;  // high byte of the error code
  std::string_view text;
};

constexpr ClassText kClasses[] = {
    {0x00, "Error reset or no error"},
    {0x10, "Generic error"},
    {0x20, "Current"},
    {0x21, "Current, CANopen device input side"},
    {0x22, "Current inside the CANopen device"},
    {0x23, "Current, CANopen device output side"},
    {0x30, "Voltage"},
    {0x31, "Mains voltage"},
    {0x32, "Voltage inside the CANopen device"},
    {0x33, "Output voltage"},
    {0x40, "Temperature"},
    {0x41, "Ambient temperature"},
    {0x42, "CANopen device temperature"},
    {0x50, "CANopen device hardware"},
    {0x60, "CANopen device software"},
    {0x61, "Internal software"},
    {0x62, "User software"},
    {0x63, "Data set"},
    {0x70, "Additional modules"},
    {0x80, "Monitoring"},
    {0x81, "Communication"},
    {0x82, "Protocol error"},
    {0x90, "External error"},
    {0xF0, "Additional functions"},
    {0xFF, "CANopen device specific"},
};

const ClassText* find_class(std::uint8_t high) {
  for (const auto& c : kClasses) {
    if (c.high == high) return &c;
  }
  return nullptr;
}

std::uint32_t get_u32(const od::ObjectDictionary& od, std::uint16_t index, std::uint32_t fallback) {
  return static_cast<std::uint32_t>(od.get_unsigned(index, 0).value_or(fallback));
}

}  // namespace

std::string_view emcy_class_description(std::uint16_t error_code) {
  const auto high = static_cast<std::uint8_t>(error_code >> 8);
  if (const ClassText* c = find_class(high)) return c->text;
  // A sub-class the table does not list (e.g. 24xxh) belongs to its
  // general class (20xxh); Fx is listed only as F0 and FF.
  if ((high & 0xF0U) != 0xF0U) {
    if (const ClassText* c = find_class(static_cast<std::uint8_t>(high & 0xF0U))) return c->text;
  }
  return "Unknown error code class";
}

std::string_view emcy_description(std::uint16_t error_code) {
  for (const auto& c : kCodes) {
    if (c.code == error_code) return c.text;
  }
  return emcy_class_description(error_code);
}

std::array<std::uint8_t, 8> encode_emcy(std::uint16_t error_code, std::uint8_t error_register,
                                        const ManufacturerField& manufacturer) {
  std::array<std::uint8_t, 8> b{};
  b[0] = static_cast<std::uint8_t>(error_code & 0xFFU);
  b[1] = static_cast<std::uint8_t>(error_code >> 8);
  b[2] = error_register;
  std::copy(manufacturer.begin(), manufacturer.end(), b.begin() + 3);
  return b;
}

// ---- producer ------------------------------------------------------------------

EmcyProducer::EmcyProducer(od::ObjectDictionary& dictionary, FrameSink sink)
    : od_(dictionary), sink_(std::move(sink)) {}

std::uint8_t EmcyProducer::error_register() const {
  if (present_.empty()) return 0;
  std::uint8_t reg = error_register::kGeneric;
  for (const auto& [code, bits] : present_) reg = static_cast<std::uint8_t>(reg | bits);
  return static_cast<std::uint8_t>(reg & ~(1U << 6));  // bit 6 is reserved (always 0)
}

void EmcyProducer::store_register() {
  (void)od_.set(0x1001, 0, Value::of_unsigned(DataType::Unsigned8, error_register()));
}

Duration EmcyProducer::inhibit() const {
  const auto n = od_.get_unsigned(0x1015, 0).value_or(0);
  return std::chrono::duration_cast<Duration>(std::chrono::microseconds(100 * static_cast<std::int64_t>(n)));
}

bool EmcyProducer::raise(std::uint16_t error_code, std::uint8_t register_bits, TimePoint now,
                         const ManufacturerField& manufacturer, std::uint16_t additional_info) {
  if (error_code == 0 || present_.contains(error_code)) return false;
  present_.emplace(error_code, register_bits);
  store_register();
  od::push_error_history(od_, static_cast<std::uint32_t>(error_code) |
                                  (static_cast<std::uint32_t>(additional_info) << 16));
  emit(error_code, manufacturer, now);
  return true;
}

bool EmcyProducer::clear(std::uint16_t error_code, TimePoint now, const ManufacturerField& manufacturer) {
  if (present_.erase(error_code) == 0) return false;
  store_register();
  emit(0x0000, manufacturer, now);
  return true;
}

void EmcyProducer::clear_all(TimePoint now) {
  if (present_.empty()) return;
  present_.clear();
  store_register();
  emit(0x0000, {}, now);
}

void EmcyProducer::emit(std::uint16_t error_code, const ManufacturerField& manufacturer, TimePoint now) {
  const std::uint32_t cob_id = get_u32(od_, 0x1014, kCobIdBit31);
  if ((cob_id & kCobIdBit31) != 0) return;  // EMCY not valid: nothing is sent
  const auto bytes = encode_emcy(error_code, error_register(), manufacturer);
  const can::Frame f = frame_for_cob_id(cob_id, bytes.data(), static_cast<std::uint8_t>(bytes.size()));
  // Queue behind earlier held-back frames to keep the order of events.
  if (!queue_.empty() || (sent_any_ && now < last_sent_ + inhibit())) {
    queue_.push_back(f);
    return;
  }
  transmit(f, now);
}

void EmcyProducer::transmit(const can::Frame& f, TimePoint now) {
  sent_any_ = true;
  last_sent_ = now;
  if (sink_) sink_(f);
}

TimePoint EmcyProducer::next_deadline() const {
  if (queue_.empty()) return TimePoint::max();
  return last_sent_ + inhibit();
}

void EmcyProducer::on_time(TimePoint now) {
  // One frame per call at most: the next one's inhibit time starts now.
  if (queue_.empty() || now < next_deadline()) return;
  // EMCY was made invalid meanwhile (the way to change its COB-ID): what is
  // held back would go out on the old COB-ID, so it is discarded.
  if ((get_u32(od_, 0x1014, kCobIdBit31) & kCobIdBit31) != 0) {
    queue_.clear();
    return;
  }
  const can::Frame f = queue_.front();
  queue_.pop_front();
  transmit(f, now);
}

// ---- consumer ------------------------------------------------------------------

EmcyConsumerConfig EmcyConsumerConfig::from_dictionary(const od::ObjectDictionary& od) {
  EmcyConsumerConfig cfg;
  const od::Object* obj = od.find(0x1028);
  if (obj == nullptr) return cfg;
  for (const auto& [sub, entry] : obj->subs) {
    if (sub == 0 || sub > 127) continue;
    // Invalid entries (bit 31) are kept: the consumer skips them, and a map
    // of only invalid entries means "consume none", not "defaults".
    if (const auto v = od.get_unsigned(0x1028, sub)) cfg.cob_ids.emplace(sub, static_cast<std::uint32_t>(*v));
  }
  // A 1028h without entries consumes nothing either.
  if (cfg.cob_ids.empty()) cfg.cob_ids.emplace(0, kCobIdBit31);
  return cfg;
}

EmcyConsumer::EmcyConsumer(EmcyConsumerConfig config, Callback callback) : callback_(std::move(callback)) {
  if (config.cob_ids.empty()) {
    for (std::uint8_t n = 1; n <= 127; ++n) nodes_.emplace(0x80U + n, n);
    return;
  }
  for (const auto& [node, cob_id] : config.cob_ids) {
    if ((cob_id & kCobIdBit31) != 0) continue;
    nodes_.emplace(can_id_of(cob_id) | (cob_id & kCobIdFrame), node);
  }
}

bool EmcyConsumer::on_frame(const can::Frame& frame, TimePoint /*now*/) {
  if (frame.remote()) return false;
  const std::uint32_t key = frame.id | (frame.extended() ? kCobIdFrame : 0U);
  const auto it = nodes_.find(key);
  if (it == nodes_.end()) return false;
  const auto p = frame.payload();
  auto byte = [&](std::size_t i) -> std::uint8_t { return i < p.size() ? p[i] : 0; };
  EmcyEvent ev;
  ev.node = it->second;
  ev.error_code = static_cast<std::uint16_t>(byte(0) | (byte(1) << 8));
  ev.error_register = byte(2);
  for (std::size_t i = 0; i < ev.manufacturer.size(); ++i) ev.manufacturer[i] = byte(3 + i);
  if (p.size() < 8) {
    ev.description = "malformed EMCY: " + std::to_string(p.size()) + " data bytes, 8 expected";
  } else {
    ev.description = std::string(emcy_description(ev.error_code));
  }
  if (callback_) callback_(ev);
  return true;
}

}  // namespace canopen::emcy
