// One sample value of every CANopen data type, as text (parse_value form),
// shared by the tests that round-trip every type.
#pragma once

#include <string_view>
#include <utility>

#include "canopen/types.hpp"

namespace canopen::test {

inline constexpr std::pair<DataType, std::string_view> kEveryTypeSamples[] = {
      {DataType::Boolean, "1"},
      {DataType::Integer8, "-100"},
      {DataType::Integer16, "-30000"},
      {DataType::Integer24, "-8388608"},
      {DataType::Integer32, "2147483647"},
      {DataType::Integer40, "-549755813888"},
      {DataType::Integer48, "140737488355327"},
      {DataType::Integer56, "-36028797018963968"},
      {DataType::Integer64, "-9223372036854775808"},
      {DataType::Unsigned8, "255"},
      {DataType::Unsigned16, "65535"},
      {DataType::Unsigned24, "16777215"},
      {DataType::Unsigned32, "4294967295"},
      {DataType::Unsigned40, "1099511627775"},
      {DataType::Unsigned48, "281474976710655"},
      {DataType::Unsigned56, "72057594037927935"},
      {DataType::Unsigned64, "18446744073709551615"},
      {DataType::Real32, "-1.25"},
      {DataType::Real64, "3.141592653589793"},
      {DataType::TimeOfDay, "2024-02-29T23:59:59.999Z"},
      {DataType::TimeDifference, "65535 86399999"},
      {DataType::VisibleString, "Device name"},
      {DataType::OctetString, "00ff10"},
      {DataType::UnicodeString, "gr\xC3\xBC\xC3\x9F"},
      {DataType::Domain, "deadbeef"},
};

}  // namespace canopen::test
