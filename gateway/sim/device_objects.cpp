#include "sim/device_objects.hpp"

#include <boost/crc.hpp>

#include "canopen/sdo/abort.hpp"

namespace canopen::sim {

namespace {

constexpr std::uint16_t kProgramData = 0x1F50, kProgramControl = 0x1F51, kProgramId = 0x1F56, kFlashStatus = 0x1F57;
// 1F51h commands and the state read back (see the header).
constexpr std::uint8_t kStop = 0, kStart = 1, kReset = 2, kClear = 3, kNoProgram = 3;

std::error_code abort(SdoAbort a) { return make_error_code(a); }

const Bytes* image_of(const od::ObjectDictionary& od, std::uint8_t n) {
  const od::SubEntry* e = od.find(kProgramData, n);
  return e == nullptr ? nullptr : std::get_if<Bytes>(&e->value.data);
}

bool has_image(const od::ObjectDictionary& od, std::uint8_t n) {
  const Bytes* b = image_of(od, n);
  return b != nullptr && !b->empty();
}

bool running(const od::ObjectDictionary& od, std::uint8_t n) {
  const auto v = od.get_unsigned(kProgramControl, n).value_or(kStop);
  return has_image(od, n) && (v == kStart || v == kReset);
}

Bytes u32(std::uint32_t v) { return encode(Value::of_unsigned(DataType::Unsigned32, v)); }

}  // namespace

std::uint32_t program_identification(std::span<const std::uint8_t> image) {
  if (image.empty()) return 0;
  boost::crc_32_type crc;
  crc.process_bytes(image.data(), image.size());
  return crc.checksum();
}

bool install_program_objects(od::ObjectDictionary& od) {
  if (od.find(kProgramControl) == nullptr) return false;
  if (od.find(kProgramData) != nullptr) {
    od.on_dict_write(kProgramData, [](od::ObjectDictionary& d, od::SubEntry& e, const Value& v) -> std::error_code {
      const auto* bytes = std::get_if<Bytes>(&v.data);
      if (bytes == nullptr || e.sub == 0) return abort(SdoAbort::UnsupportedAccess);
      if (bytes->size() > kMaxProgramSize) return abort(SdoAbort::OutOfMemory);
      if (running(d, e.sub)) return abort(SdoAbort::CannotStoreDeviceState);
      // A new image is there, not running.
      if (d.find(kProgramControl, e.sub) != nullptr)
        (void)d.set(kProgramControl, e.sub, Value::of_unsigned(DataType::Unsigned8, kStop));
      return {};
    });
  }
  od.on_dict_read(kProgramControl, [](const od::ObjectDictionary& d, const od::SubEntry& e) -> Result<Bytes> {
    if (e.sub == 0) return encode(e.value);
    const std::uint8_t state = !has_image(d, e.sub) ? kNoProgram : running(d, e.sub) ? kStart : kStop;
    return encode(Value::of_unsigned(DataType::Unsigned8, state));
  });
  od.on_dict_write(kProgramControl, [](od::ObjectDictionary& d, od::SubEntry& e, const Value& v) -> std::error_code {
    const auto* cmd = std::get_if<std::uint64_t>(&v.data);
    if (e.sub == 0 || cmd == nullptr) return abort(SdoAbort::UnsupportedAccess);
    switch (*cmd) {
      case kStop: return {};
      case kStart:
      case kReset:
        return has_image(d, e.sub) ? std::error_code{} : abort(SdoAbort::CannotStoreDeviceState);
      case kClear:
        if (running(d, e.sub)) return abort(SdoAbort::CannotStoreDeviceState);
        if (const od::SubEntry* data = d.find(kProgramData, e.sub); data != nullptr)
          (void)d.set(kProgramData, e.sub, Value::of_bytes(data->type, {}));
        return {};
      default: return abort(SdoAbort::InvalidValue);
    }
  });
  if (od.find(kProgramId) != nullptr) {
    od.on_dict_read(kProgramId, [](const od::ObjectDictionary& d, const od::SubEntry& e) -> Result<Bytes> {
      if (e.sub == 0) return encode(e.value);
      const Bytes* image = image_of(d, e.sub);
      return u32(image == nullptr ? 0 : program_identification(*image));
    });
  }
  if (od.find(kFlashStatus) != nullptr) {
    od.on_dict_read(kFlashStatus, [](const od::ObjectDictionary&, const od::SubEntry& e) -> Result<Bytes> {
      if (e.sub == 0) return encode(e.value);
      return u32(0);  // no error
    });
  }
  return true;
}

}  // namespace canopen::sim
