// Tests for stack/src/lss/error.cpp: the LSS error category keeps the
// service and the CiA 305 error value of a slave's answer (facts C.1).
#include <gtest/gtest.h>

#include "canopen/lss/error.hpp"
#include "canopen/lss/frames.hpp"

namespace canopen::lss {
namespace {

TEST(LssError, SlaveAnswersKeepServiceAndCiaValueFactsC1) {
  EXPECT_EQ(slave_error(cs::ConfigureNodeId, 1), make_error_code(LssError::NodeIdOutOfRange));
  EXPECT_EQ(slave_error(cs::ConfigureBitTiming, 1), make_error_code(LssError::BitTimingNotSupported));
  EXPECT_EQ(slave_error(cs::StoreConfiguration, 2), make_error_code(LssError::StoreMediaAccess));
  EXPECT_EQ(slave_error_byte(make_error_code(LssError::StoreManufacturer)), 0xFF);
  EXPECT_EQ(slave_error_byte(make_error_code(LssError::StoreNotSupported)), 1);
  EXPECT_FALSE(slave_error_byte(make_error_code(LssError::Timeout)).has_value());
  EXPECT_FALSE(slave_error_byte(std::make_error_code(std::errc::invalid_argument)).has_value());
}

TEST(LssError, MessagesSayWhatHappened) {
  EXPECT_EQ(make_error_code(LssError::StoreMediaAccess).message(), "LSS slave: storage media access error");
  EXPECT_EQ(make_error_code(LssError::NoUnconfiguredSlave).message(), "no unconfigured LSS slave answered");
  EXPECT_EQ(slave_error(cs::StoreConfiguration, 3).message(), "LSS slave: reserved error code 3");
  EXPECT_STREQ(lss_category().name(), "lss");
}

}  // namespace
}  // namespace canopen::lss
