// SDO abort codes (CiA 301 7.2.4.3.17, table 22) as an std::error_code category.
#include "canopen/sdo/abort.hpp"

#include <gtest/gtest.h>

#include <system_error>
#include <type_traits>

namespace canopen {
namespace {

static_assert(std::is_error_code_enum_v<SdoAbort>);

TEST(SdoAbortCategory, ValueIsTheCiaCode) {
  std::error_code ec = SdoAbort::Timeout;  // implicit, via is_error_code_enum
  EXPECT_EQ(ec.value(), 0x05040000);
  EXPECT_EQ(&ec.category(), &sdo_abort_category());
  EXPECT_STREQ(ec.category().name(), "sdo-abort");
  EXPECT_TRUE(ec);
  EXPECT_EQ(ec, SdoAbort::Timeout);
  EXPECT_NE(ec, SdoAbort::ToggleNotAlternated);
  EXPECT_EQ(to_abort_code(ec), 0x05040000u);
  // Codes with the top bit region set survive the int round trip.
  EXPECT_EQ(to_abort_code(make_error_code(SdoAbort::NoDataAvailable)), 0x08000024u);
  EXPECT_EQ(to_abort_code(make_error_code(SdoAbort::ValueTooHigh)), 0x06090031u);
}

TEST(SdoAbortCategory, MessageIsTheStandardText) {
  EXPECT_EQ(make_error_code(SdoAbort::NoSuchObject).message(), "Object does not exist in the object dictionary");
  EXPECT_EQ(make_error_code(SdoAbort::ToggleNotAlternated).message(), "Toggle bit not alternated");
  EXPECT_EQ(make_error_code(SdoAbort::LengthTooHigh).message(),
            "Data type does not match, length of service parameter too high");
  EXPECT_EQ(make_error_code(SdoAbort::ValueTooLow).message(), "Value of parameter written too low (download only)");
  EXPECT_EQ(make_error_code(SdoAbort::GeneralError).message(), "General error");
  EXPECT_EQ(sdo_abort_text(0x06020000), "Object does not exist in the object dictionary");
  EXPECT_EQ(sdo_abort_text(0x12345678), "Reserved abort code");
  EXPECT_EQ(sdo_abort_category().message(0x12345678), "Reserved abort code");
}

TEST(SdoAbortCategory, ForeignCodesAreGeneralError) {
  EXPECT_EQ(to_abort_code(std::make_error_code(std::errc::timed_out)), 0x08000000u);
  EXPECT_EQ(to_abort_code(std::make_error_code(std::errc::invalid_argument)), 0x08000000u);
  // Even a foreign code whose value happens to be an abort code.
  EXPECT_EQ(to_abort_code(std::error_code(0x05040000, std::generic_category())), 0x08000000u);
  // No error at all is not an abort code either (system category, value 0).
  EXPECT_EQ(to_abort_code(std::error_code{}), 0x08000000u);
}

}  // namespace
}  // namespace canopen
