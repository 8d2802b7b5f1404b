// Tests for stack/src/od/gateway_dictionary.cpp: the communication objects of
// CiA 301 7.5.2 and their value rules, one test per rule. Every refused write
// is checked for its exact abort code and for leaving the dictionary unchanged.
#include "canopen/od/gateway_dictionary.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <initializer_list>
#include <map>
#include <utility>
#include <vector>

namespace canopen::od {
namespace {

constexpr std::uint8_t kNode = 5;
using Indexes = std::initializer_list<std::uint16_t>;

Bytes le(std::uint64_t v, std::size_t n) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(v >> (8 * i));
  return b;
}

std::uint32_t abort_code(std::error_code ec) { return ec ? to_abort_code(ec) : 0U; }

std::map<std::pair<std::uint16_t, std::uint8_t>, Value> snapshot(const ObjectDictionary& od) {
  std::map<std::pair<std::uint16_t, std::uint8_t>, Value> out;
  for (const auto& [index, obj] : od.objects()) {
    for (const auto& [sub, e] : obj.subs) out.emplace(std::pair{index, sub}, e.value);
  }
  return out;
}

GatewayIdentity identity() {
  GatewayIdentity id;
  id.device_type = 0x000F0191;
  id.vendor_id = 0x0000ABCD;
  id.product_code = 0x00001234;
  id.revision = 0x00010002;
  id.serial = 0xCAFEF00D;
  id.device_name = "gw";
  id.hardware_version = "hw1";
  id.software_version = "0.1.0";
  return id;
}

class GatewayDictionary : public ::testing::Test {
 protected:
  ObjectDictionary od = make_gateway_dictionary(kNode, identity());

  std::error_code w8(std::uint16_t i, std::uint8_t s, std::uint64_t v) { return od.write(i, s, le(v, 1)); }
  std::error_code w16(std::uint16_t i, std::uint8_t s, std::uint64_t v) { return od.write(i, s, le(v, 2)); }
  std::error_code w32(std::uint16_t i, std::uint8_t s, std::uint64_t v) { return od.write(i, s, le(v, 4)); }
  std::uint64_t u(std::uint16_t i, std::uint8_t s) const { return od.get_unsigned(i, s).value(); }

  // Expects a write of a u32 to be refused with `code` and to change nothing.
  void refused32(std::uint16_t i, std::uint8_t s, std::uint64_t v, std::uint32_t code) {
    const auto before = snapshot(od);
    EXPECT_EQ(abort_code(w32(i, s, v)), code) << std::hex << i << " sub " << unsigned{s} << " value " << v;
    EXPECT_EQ(snapshot(od), before);
  }
  void refused8(std::uint16_t i, std::uint8_t s, std::uint64_t v, std::uint32_t code) {
    const auto before = snapshot(od);
    EXPECT_EQ(abort_code(w8(i, s, v)), code) << std::hex << i << " sub " << unsigned{s} << " value " << v;
    EXPECT_EQ(snapshot(od), before);
  }
  void refused16(std::uint16_t i, std::uint8_t s, std::uint64_t v, std::uint32_t code) {
    const auto before = snapshot(od);
    EXPECT_EQ(abort_code(w16(i, s, v)), code) << std::hex << i << " sub " << unsigned{s} << " value " << v;
    EXPECT_EQ(snapshot(od), before);
  }

  // A mappable u32 (rw) at 2000h and u16 rwr / rww at 2001h / 2002h.
  void add_application_objects() {
    od.insert(make_var(0x2000, "u32", DataType::Unsigned32, Access::ReadWrite,
                       Value::of_unsigned(DataType::Unsigned32, 0), true));
    od.insert(make_var(0x2001, "tx only", DataType::Unsigned16, Access::ReadWriteRead,
                       Value::of_unsigned(DataType::Unsigned16, 0), true));
    od.insert(make_var(0x2002, "rx only", DataType::Unsigned16, Access::ReadWriteWrite,
                       Value::of_unsigned(DataType::Unsigned16, 0), true));
    od.insert(make_var(0x2003, "not mappable", DataType::Unsigned16, Access::ReadWrite,
                       Value::of_unsigned(DataType::Unsigned16, 0), false));
    od.insert(make_var(0x2004, "text", DataType::VisibleString, Access::ReadWrite, Value::of_string("x"), true));
  }
};

// ---- overall -------------------------------------------------------------------------

TEST_F(GatewayDictionary, Od7_5_2_HasTheCommunicationObjects) {
  for (std::uint16_t i : Indexes{0x1000, 0x1001, 0x1003, 0x1005, 0x1006, 0x1007, 0x1008, 0x1009, 0x100A, 0x100C, 0x100D,
                          0x1010, 0x1011, 0x1012, 0x1013, 0x1014, 0x1015, 0x1016, 0x1017, 0x1018, 0x1019, 0x1200,
                          0x1280, 0x1400, 0x1403, 0x1600, 0x1603, 0x1800, 0x1803, 0x1A00, 0x1A03}) {
    EXPECT_NE(od.find(i), nullptr) << std::hex << i;
  }
  for (std::uint16_t i : Indexes{0x1002, 0x1004, 0x100B, 0x1404, 0x1604, 0x1804, 0x1A04}) {
    EXPECT_EQ(od.find(i), nullptr) << std::hex << i;
  }
}

TEST_F(GatewayDictionary, HooksFollowTheDictionaryWhenCopiedOrMoved) {
  ObjectDictionary copy = od;
  ASSERT_FALSE(copy.write(0x1006, 0, le(1000, 4)));
  // 1019h looks at the 1006h of the dictionary it is in.
  EXPECT_EQ(abort_code(copy.write(0x1019, 0, le(10, 1))), 0x08000022U);
  EXPECT_FALSE(od.write(0x1019, 0, le(10, 1)));
  ObjectDictionary moved = std::move(copy);
  EXPECT_EQ(abort_code(moved.write(0x1019, 0, le(20, 1))), 0x08000022U);
}

// ---- 7.5.2.1 / 7.5.2.2 ---------------------------------------------------------------

TEST_F(GatewayDictionary, Od1000h_DeviceTypeIsReadOnly) {
  EXPECT_EQ(od.read(0x1000, 0).value(), le(0x000F0191, 4));
  refused32(0x1000, 0, 0, 0x06010002U);
}

TEST_F(GatewayDictionary, Od1001h_ErrorRegisterIsReadOnlyAndPdoMappable) {
  EXPECT_EQ(od.read(0x1001, 0).value(), Bytes{0});
  EXPECT_TRUE(od.find(0x1001, 0)->pdo_mappable);
  refused8(0x1001, 0, 1, 0x06010002U);
}

// ---- 7.5.2.4 1003h ------------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1003h_StartsEmptyWithTheConfiguredSize) {
  EXPECT_EQ(u(0x1003, 0), 0U);
  EXPECT_EQ(od.find(0x1003)->subs.size(), 9U);  // sub 0 + 8 (default)
  EXPECT_EQ(od.find(0x1003, 0)->access, Access::ReadWrite);
  EXPECT_EQ(od.find(0x1003, 1)->type, DataType::Unsigned32);
}

TEST_F(GatewayDictionary, Od1003h_SizeComesFromOptionsAndZeroLeavesItOut) {
  GatewayDictionaryOptions o;
  o.error_history_size = 2;
  EXPECT_EQ(make_gateway_dictionary(kNode, identity(), o).find(0x1003)->subs.size(), 3U);
  o.error_history_size = 0;
  EXPECT_EQ(make_gateway_dictionary(kNode, identity(), o).find(0x1003), nullptr);
}

TEST_F(GatewayDictionary, Od1003h_ReadingPastTheNumberOfErrorsAbortsNoDataAvailable) {
  EXPECT_EQ(abort_code(od.read(0x1003, 1).code()), 0x08000024U);
  push_error_history(od, 0x00001000);
  EXPECT_EQ(od.read(0x1003, 1).value(), le(0x00001000, 4));
  EXPECT_EQ(abort_code(od.read(0x1003, 2).code()), 0x08000024U);
  EXPECT_EQ(abort_code(od.read(0x1003, 8).code()), 0x08000024U);
  EXPECT_EQ(abort_code(od.read(0x1003, 9).code()), 0x06090011U);  // past the array
}

TEST_F(GatewayDictionary, Od1003h_NewestErrorIsAtSub1OlderOnesShiftDown) {
  push_error_history(od, 0x11111000);
  push_error_history(od, 0x22222000);
  push_error_history(od, 0x33333000);
  EXPECT_EQ(u(0x1003, 0), 3U);
  EXPECT_EQ(u(0x1003, 1), 0x33333000U);
  EXPECT_EQ(u(0x1003, 2), 0x22222000U);
  EXPECT_EQ(u(0x1003, 3), 0x11111000U);
  EXPECT_EQ(od.read(0x1003, 0).value(), Bytes{3});
}

TEST_F(GatewayDictionary, Od1003h_OldestErrorFallsOffWhenFull) {
  for (std::uint32_t e = 1; e <= 10; ++e) push_error_history(od, e);
  EXPECT_EQ(u(0x1003, 0), 8U);
  for (std::uint8_t s = 1; s <= 8; ++s) EXPECT_EQ(u(0x1003, s), 11U - s);  // 10 newest ... 3 oldest
}

TEST_F(GatewayDictionary, Od1003h_PushWithoutTheObjectIsANoOp) {
  ObjectDictionary empty;
  push_error_history(empty, 1);
  EXPECT_TRUE(empty.objects().empty());
}

TEST_F(GatewayDictionary, Od1003h_WritingZeroToSub0ClearsHistory) {
  push_error_history(od, 0x1000);
  push_error_history(od, 0x2000);
  EXPECT_FALSE(w8(0x1003, 0, 0));
  EXPECT_EQ(u(0x1003, 0), 0U);
  EXPECT_EQ(u(0x1003, 1), 0U);
  EXPECT_EQ(u(0x1003, 2), 0U);
  EXPECT_EQ(abort_code(od.read(0x1003, 1).code()), 0x08000024U);
}

TEST_F(GatewayDictionary, Od1003h_WritingNonZeroToSub0AbortsInvalidValue) {
  push_error_history(od, 0x1000);
  refused8(0x1003, 0, 1, 0x06090030U);
  refused8(0x1003, 0, 0xFE, 0x06090030U);
  EXPECT_EQ(u(0x1003, 0), 1U);
}

TEST_F(GatewayDictionary, Od1003h_ErrorEntriesAreReadOnly) {
  push_error_history(od, 0x1000);
  refused32(0x1003, 1, 0, 0x06010002U);
}

// ---- 7.5.2.5 1005h ---------------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1005h_DefaultIs80hWithoutGeneration) { EXPECT_EQ(u(0x1005, 0), 0x00000080U); }

TEST_F(GatewayDictionary, Od1005h_CanIdChangesWhileNotGenerating) {
  EXPECT_FALSE(w32(0x1005, 0, 0x00000081));
  EXPECT_EQ(u(0x1005, 0), 0x81U);
}

TEST_F(GatewayDictionary, Od1005h_GenerateBitSetsAndClearsWithTheSameCanId) {
  EXPECT_FALSE(w32(0x1005, 0, 0x40000080));
  EXPECT_EQ(u(0x1005, 0), 0x40000080U);
  EXPECT_FALSE(w32(0x1005, 0, 0x00000080));
  EXPECT_EQ(u(0x1005, 0), 0x00000080U);
}

TEST_F(GatewayDictionary, Od1005h_CanIdMustNotChangeWhileGenerating) {
  ASSERT_FALSE(w32(0x1005, 0, 0x40000080));
  refused32(0x1005, 0, 0x40000081, 0x06090030U);
  refused32(0x1005, 0, 0x00000081, 0x06090030U);  // clearing bit 30 and changing at once
  refused32(0x1005, 0, 0x60000080, 0x06090030U);  // frame bit is part of bits 0..29
}

TEST_F(GatewayDictionary, Od1005h_29BitCanIdOnlyWithFrameBit) {
  refused32(0x1005, 0, 0x00012345, 0x06090030U);
  EXPECT_FALSE(w32(0x1005, 0, 0x20012345));
  EXPECT_EQ(u(0x1005, 0), 0x20012345U);
}

TEST_F(GatewayDictionary, Od1005h_RestrictedCanIdsOf7_3_5AreRejected) {
  for (std::uint32_t id : {0x000U, 0x001U, 0x07FU, 0x101U, 0x180U, 0x581U, 0x5FFU, 0x601U, 0x67FU, 0x6E0U, 0x6FFU,
                           0x701U, 0x77FU, 0x780U, 0x7FFU}) {
    refused32(0x1005, 0, id, 0x06090030U);
  }
  for (std::uint32_t id : {0x080U, 0x100U, 0x181U, 0x580U, 0x600U, 0x680U, 0x6DFU, 0x700U}) {
    EXPECT_FALSE(w32(0x1005, 0, id)) << std::hex << id;
  }
}

// ---- 7.5.2.6 - 7.5.2.12 ------------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1006h_1007h_AreReadWriteAndStartAtZero) {
  for (std::uint16_t i : Indexes{0x1006, 0x1007}) {
    EXPECT_EQ(u(i, 0), 0U);
    EXPECT_FALSE(w32(i, 0, 10000));
    EXPECT_EQ(od.read(i, 0).value(), le(10000, 4));
  }
}

TEST_F(GatewayDictionary, Od1008h_1009h_100Ah_StringsAreConstAndReadAsTheirBytes) {
  EXPECT_EQ(od.read(0x1008, 0).value(), (Bytes{'g', 'w'}));
  EXPECT_EQ(od.read(0x1009, 0).value(), (Bytes{'h', 'w', '1'}));
  EXPECT_EQ(od.read(0x100A, 0).value(), (Bytes{'0', '.', '1', '.', '0'}));
  EXPECT_EQ(od.upload_size(0x1008, 0), 2U);
  const auto before = snapshot(od);
  for (std::uint16_t i : Indexes{0x1008, 0x1009, 0x100A}) {
    EXPECT_EQ(od.find(i, 0)->access, Access::Const);
    EXPECT_EQ(abort_code(od.write(i, 0, Bytes{'x'})), 0x06010002U);
  }
  EXPECT_EQ(snapshot(od), before);
}

TEST_F(GatewayDictionary, Od100Ch_100Dh_LifeGuardingParametersAreReadWrite) {
  EXPECT_FALSE(w16(0x100C, 0, 100));
  EXPECT_FALSE(w8(0x100D, 0, 3));
  EXPECT_EQ(u(0x100C, 0), 100U);
  EXPECT_EQ(u(0x100D, 0), 3U);
  refused32(0x100C, 0, 100, 0x06070012U);
}

// ---- 7.5.2.13 / 7.5.2.14 -----------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1010h_SaveSignatureIsAcceptedAndCallsTheCallback) {
  std::vector<std::uint8_t> subs;
  GatewayDictionaryOptions o;
  o.on_store = [&](std::uint8_t sub) {
    subs.push_back(sub);
    return std::error_code{};
  };
  od = make_gateway_dictionary(kNode, identity(), o);
  EXPECT_FALSE(w32(0x1010, 1, 0x65766173));
  EXPECT_FALSE(w32(0x1010, 3, 0x65766173));
  EXPECT_EQ(subs, (std::vector<std::uint8_t>{1, 3}));
}

TEST_F(GatewayDictionary, Od1010h_SaveWithoutCallbackIsAccepted) { EXPECT_FALSE(w32(0x1010, 2, 0x65766173)); }

TEST_F(GatewayDictionary, Od1010h_WrongSignatureAbortsCannotStore) {
  bool called = false;
  GatewayDictionaryOptions o;
  o.on_store = [&](std::uint8_t) {
    called = true;
    return std::error_code{};
  };
  od = make_gateway_dictionary(kNode, identity(), o);
  refused32(0x1010, 1, 0x73617665, 0x08000020U);  // "save" in the wrong byte order
  refused32(0x1010, 1, 0x64616F6C, 0x08000020U);  // "load"
  refused32(0x1010, 1, 0, 0x08000020U);
  EXPECT_FALSE(called);
}

TEST_F(GatewayDictionary, Od1010h_CallbackErrorAbortsTheDownload) {
  GatewayDictionaryOptions o;
  o.on_store = [](std::uint8_t) { return make_error_code(SdoAbort::HardwareError); };
  od = make_gateway_dictionary(kNode, identity(), o);
  EXPECT_EQ(abort_code(w32(0x1010, 1, 0x65766173)), 0x06060000U);
}

TEST_F(GatewayDictionary, Od1010h_ReadGivesTheCapabilitySaveOnCommand) {
  EXPECT_EQ(u(0x1010, 0), 3U);
  EXPECT_EQ(od.find(0x1010, 0)->access, Access::Const);
  EXPECT_EQ(od.read(0x1010, 1).value(), le(1, 4));
  ASSERT_FALSE(w32(0x1010, 1, 0x65766173));
  EXPECT_EQ(od.read(0x1010, 1).value(), le(1, 4));  // not the signature
}

TEST_F(GatewayDictionary, Od1011h_LoadSignatureIsAcceptedAndCallsTheCallback) {
  std::vector<std::uint8_t> subs;
  GatewayDictionaryOptions o;
  o.on_restore = [&](std::uint8_t sub) {
    subs.push_back(sub);
    return std::error_code{};
  };
  od = make_gateway_dictionary(kNode, identity(), o);
  EXPECT_FALSE(w32(0x1011, 2, 0x64616F6C));
  EXPECT_EQ(subs, (std::vector<std::uint8_t>{2}));
  EXPECT_EQ(od.read(0x1011, 2).value(), le(1, 4));
}

TEST_F(GatewayDictionary, Od1011h_WrongSignatureAbortsCannotStore) {
  refused32(0x1011, 1, 0x65766173, 0x08000020U);  // "save"
  refused32(0x1011, 1, 1, 0x08000020U);
}

// ---- 7.5.2.15 1012h ----------------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1012h_DefaultIs100hUnused) { EXPECT_EQ(u(0x1012, 0), 0x00000100U); }

TEST_F(GatewayDictionary, Od1012h_CanIdMustNotChangeWhileConsumingOrProducing) {
  ASSERT_FALSE(w32(0x1012, 0, 0x80000100));  // consumer
  refused32(0x1012, 0, 0x80000101 + 0x100, 0x06090030U);
  ASSERT_FALSE(w32(0x1012, 0, 0x40000100));  // producer instead: only bits 30/31 changed
  refused32(0x1012, 0, 0x40000281, 0x06090030U);
  ASSERT_FALSE(w32(0x1012, 0, 0x00000100));
  EXPECT_FALSE(w32(0x1012, 0, 0x00000281));
}

TEST_F(GatewayDictionary, Od1012h_29BitCanIdOnlyWithFrameBit) {
  refused32(0x1012, 0, 0x00001234, 0x06090030U);
  EXPECT_FALSE(w32(0x1012, 0, 0x20001234));
}

TEST_F(GatewayDictionary, Od1012h_RestrictedCanIdRejectedWhileInUse) {
  refused32(0x1012, 0, 0x80000000 | 0x101, 0x06090030U);
  refused32(0x1012, 0, 0x40000000 | 0x701, 0x06090030U);
}

// ---- 7.5.2.16 - 7.5.2.18 ------------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1013h_HighResolutionTimeStampIsReadWriteAndMappable) {
  EXPECT_TRUE(od.find(0x1013, 0)->pdo_mappable);
  EXPECT_FALSE(w32(0x1013, 0, 123456));
  EXPECT_EQ(u(0x1013, 0), 123456U);
}

TEST_F(GatewayDictionary, Od1014h_DefaultIs80hPlusNodeIdValid) { EXPECT_EQ(u(0x1014, 0), 0x80U + kNode); }

TEST_F(GatewayDictionary, Od1014h_CanIdMustNotChangeWhileValid) {
  refused32(0x1014, 0, 0x000000A0, 0x06090030U);
  refused32(0x1014, 0, 0x800000A0, 0x06090030U);  // invalidating and changing at once
}

TEST_F(GatewayDictionary, Od1014h_CanIdChangesWhileInvalid) {
  ASSERT_FALSE(w32(0x1014, 0, 0x80000085));
  ASSERT_FALSE(w32(0x1014, 0, 0x800000A0));
  ASSERT_FALSE(w32(0x1014, 0, 0x000000A0));
  EXPECT_EQ(u(0x1014, 0), 0xA0U);
}

TEST_F(GatewayDictionary, Od1014h_Bit30IsReservedZero) { refused32(0x1014, 0, 0x40000085, 0x06090030U); }

TEST_F(GatewayDictionary, Od1014h_RestrictedOr29BitWithoutFrameRejected) {
  ASSERT_FALSE(w32(0x1014, 0, 0x80000085));
  refused32(0x1014, 0, 0x80012345, 0x06090030U);  // 29-bit id, frame bit clear
  ASSERT_FALSE(w32(0x1014, 0, 0x80000701));    // invalid: not checked yet
  refused32(0x1014, 0, 0x00000701, 0x06090030U);
}

TEST_F(GatewayDictionary, Od1015h_InhibitTimeEmcyIsReadWriteU16) {
  EXPECT_FALSE(w16(0x1015, 0, 50));
  EXPECT_EQ(u(0x1015, 0), 50U);
  refused8(0x1015, 0, 50, 0x06070013U);
}

// ---- 7.5.2.19 1016h ---------------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1016h_EntriesHoldNodeIdAndTime) {
  EXPECT_EQ(u(0x1016, 0), 8U);
  EXPECT_EQ(od.find(0x1016, 0)->access, Access::Const);
  EXPECT_FALSE(w32(0x1016, 1, 0x000301F4));  // node 3, 500 ms
  EXPECT_EQ(u(0x1016, 1), 0x000301F4U);
}

TEST_F(GatewayDictionary, Od1016h_DuplicateNodeIdIsRejected) {
  ASSERT_FALSE(w32(0x1016, 1, 0x000301F4));
  refused32(0x1016, 2, 0x000303E8, 0x06040043U);
}

TEST_F(GatewayDictionary, Od1016h_SameNodeIdAllowedWhenOneTimeIsZero) {
  ASSERT_FALSE(w32(0x1016, 1, 0x00030000));  // node 3, time 0: unused
  EXPECT_FALSE(w32(0x1016, 2, 0x000303E8));
  EXPECT_FALSE(w32(0x1016, 3, 0x00030000));  // again unused
}

TEST_F(GatewayDictionary, Od1016h_RewritingTheSameEntryIsAllowed) {
  ASSERT_FALSE(w32(0x1016, 1, 0x000301F4));
  EXPECT_FALSE(w32(0x1016, 1, 0x000303E8));
  EXPECT_EQ(u(0x1016, 1), 0x000303E8U);
}

TEST_F(GatewayDictionary, Od1016h_NodeIdZeroOrAbove127IsUnusedAndNeverConflicts) {
  ASSERT_FALSE(w32(0x1016, 1, 0x008001F4));
  EXPECT_FALSE(w32(0x1016, 2, 0x008001F4));
  ASSERT_FALSE(w32(0x1016, 3, 0x000001F4));
  EXPECT_FALSE(w32(0x1016, 4, 0x000001F4));
}

TEST_F(GatewayDictionary, Od1016h_SizeComesFromOptions) {
  GatewayDictionaryOptions o;
  o.heartbeat_consumers = 3;
  ObjectDictionary d = make_gateway_dictionary(kNode, identity(), o);
  EXPECT_EQ(d.get_unsigned(0x1016, 0), 3U);
  EXPECT_EQ(d.find(0x1016)->subs.size(), 4U);
}

// ---- 7.5.2.20 - 7.5.2.22 ---------------------------------------------------------------------

TEST_F(GatewayDictionary, Od1017h_ProducerHeartbeatTimeIsReadWriteU16) {
  EXPECT_EQ(u(0x1017, 0), 0U);
  EXPECT_FALSE(w16(0x1017, 0, 1000));
  EXPECT_EQ(u(0x1017, 0), 1000U);
}

TEST_F(GatewayDictionary, Od1018h_IdentityRecordIsReadOnly) {
  EXPECT_EQ(od.find(0x1018)->code, ObjectCode::Record);
  EXPECT_EQ(u(0x1018, 0), 4U);
  EXPECT_EQ(od.read(0x1018, 1).value(), le(0x0000ABCD, 4));
  EXPECT_EQ(od.read(0x1018, 2).value(), le(0x00001234, 4));
  EXPECT_EQ(od.read(0x1018, 3).value(), le(0x00010002, 4));
  EXPECT_EQ(od.read(0x1018, 4).value(), le(0xCAFEF00D, 4));
  refused32(0x1018, 1, 1, 0x06010002U);
  refused8(0x1018, 0, 1, 0x06010002U);
  EXPECT_EQ(abort_code(od.read(0x1018, 5).code()), 0x06090011U);
}

TEST_F(GatewayDictionary, Od1019h_ZeroAndTwoTo240AreAccepted) {
  for (std::uint64_t v : {2U, 100U, 240U, 0U}) {
    EXPECT_FALSE(w8(0x1019, 0, v)) << v;
    EXPECT_EQ(u(0x1019, 0), v);
  }
}

TEST_F(GatewayDictionary, Od1019h_OneAndAbove240AreInvalid) {
  for (std::uint64_t v : {1U, 241U, 255U}) refused8(0x1019, 0, v, 0x06090030U);
}

TEST_F(GatewayDictionary, Od1019h_ChangeWhileCyclePeriodIsNonZeroAbortsDeviceState) {
  ASSERT_FALSE(w32(0x1005, 0, 0x40000080));
  ASSERT_FALSE(w32(0x1006, 0, 10000));
  refused8(0x1019, 0, 10, 0x08000022U);
  EXPECT_FALSE(w8(0x1019, 0, 0));  // unchanged value: no change
  ASSERT_FALSE(w32(0x1006, 0, 0));
  EXPECT_FALSE(w8(0x1019, 0, 10));
}

// ---- 7.5.2.33 / 7.5.2.34 SDO parameters -------------------------------------------------------

TEST_F(GatewayDictionary, Od1200h_DefaultServerUses600hAnd580hPlusNodeIdFixed) {
  EXPECT_EQ(u(0x1200, 0), 2U);
  EXPECT_EQ(u(0x1200, 1), 0x600U + kNode);
  EXPECT_EQ(u(0x1200, 2), 0x580U + kNode);
  refused32(0x1200, 1, 0x600U + kNode, 0x06010002U);
  refused32(0x1200, 2, 0x80000000U, 0x06010002U);
  EXPECT_EQ(abort_code(od.read(0x1200, 3).code()), 0x06090011U);
}

TEST_F(GatewayDictionary, Od1280h_OneClientChannelPerOptionFrom1280h) {
  EXPECT_NE(od.find(0x12FE), nullptr);  // 127 by default
  EXPECT_EQ(od.find(0x12FF), nullptr);
  GatewayDictionaryOptions o;
  o.sdo_clients = 3;
  ObjectDictionary d = make_gateway_dictionary(kNode, identity(), o);
  EXPECT_NE(d.find(0x1282), nullptr);
  EXPECT_EQ(d.find(0x1283), nullptr);
}

TEST_F(GatewayDictionary, Od1280h_ChannelKTalksToNodeKPlus1DefaultServer) {
  EXPECT_EQ(u(0x1282, 0), 3U);
  EXPECT_EQ(u(0x1282, 1), 0x603U);
  EXPECT_EQ(u(0x1282, 2), 0x583U);
  EXPECT_EQ(u(0x1282, 3), 3U);
  EXPECT_EQ(u(0x12FE, 1), 0x67FU);
}

TEST_F(GatewayDictionary, Od1280h_ChannelToTheGatewaysOwnNodeIdIsInvalid) {
  EXPECT_EQ(u(0x1280 + kNode - 1, 1), 0x80000000U | (0x600U + kNode));
  EXPECT_EQ(u(0x1280 + kNode - 1, 2), 0x80000000U | (0x580U + kNode));
}

TEST_F(GatewayDictionary, Od1280h_CobIdMustNotChangeWhileValid) {
  refused32(0x1280, 1, 0x00000610, 0x06090030U);
  refused32(0x1280, 2, 0x80000590, 0x06090030U);
  EXPECT_FALSE(w32(0x1280, 1, 0x40000601));  // the dyn bit may change
}

TEST_F(GatewayDictionary, Od1280h_CobIdChangesWhileInvalidAndMayUseDefaultSdoIds) {
  ASSERT_FALSE(w32(0x1280, 1, 0x80000601));
  ASSERT_FALSE(w32(0x1280, 1, 0x80000610));
  EXPECT_FALSE(w32(0x1280, 1, 0x00000610));
  EXPECT_EQ(u(0x1280, 1), 0x610U);
}

TEST_F(GatewayDictionary, Od1280h_OtherRestrictedCanIdsAreRejected) {
  ASSERT_FALSE(w32(0x1280, 2, 0x80000581));
  ASSERT_FALSE(w32(0x1280, 2, 0x80000701));
  refused32(0x1280, 2, 0x00000701, 0x06090030U);
}

TEST_F(GatewayDictionary, Od1280h_ServerNodeIdIs1To127) {
  refused8(0x1280, 3, 0, 0x06090032U);
  refused8(0x1280, 3, 128, 0x06090031U);
  EXPECT_FALSE(w8(0x1280, 3, 127));
}

// ---- 7.5.2.35 / 7.5.2.37 PDO communication ----------------------------------------------------

TEST_F(GatewayDictionary, Od1400h_1800h_PredefinedConnectionSetCobIdsStartInvalid) {
  for (unsigned n = 0; n < 4; ++n) {
    EXPECT_EQ(u(static_cast<std::uint16_t>(0x1400 + n), 1), 0x80000000U | (0x200U + 0x100U * n + kNode));
    EXPECT_EQ(u(static_cast<std::uint16_t>(0x1800 + n), 1), 0x80000000U | (0x180U + 0x100U * n + kNode));
  }
}

TEST_F(GatewayDictionary, Od1404h_1804h_FurtherPdosStartInvalidWithoutCanId) {
  GatewayDictionaryOptions o;
  o.rpdos = 5;
  o.tpdos = 6;
  ObjectDictionary d = make_gateway_dictionary(kNode, identity(), o);
  EXPECT_EQ(d.get_unsigned(0x1404, 1), 0x80000000U);
  EXPECT_EQ(d.get_unsigned(0x1805, 1), 0x80000000U);
  EXPECT_NE(d.find(0x1604), nullptr);
  EXPECT_NE(d.find(0x1A05), nullptr);
  EXPECT_EQ(d.find(0x1405), nullptr);
}

TEST_F(GatewayDictionary, Od1400h_RecordLayoutHasNoSub4AndNoSyncStart) {
  EXPECT_EQ(u(0x1400, 0), 5U);
  EXPECT_EQ(u(0x1400, 2), 0xFEU);
  EXPECT_EQ(abort_code(od.read(0x1400, 4).code()), 0x06090011U);
  EXPECT_EQ(abort_code(od.read(0x1400, 6).code()), 0x06090011U);
  refused8(0x1400, 6, 1, 0x06090011U);
  refused8(0x1400, 0, 6, 0x06010002U);
}

TEST_F(GatewayDictionary, Od1800h_RecordLayoutHasNoSub4) {
  EXPECT_EQ(u(0x1800, 0), 6U);
  EXPECT_EQ(abort_code(od.read(0x1800, 4).code()), 0x06090011U);
  refused8(0x1800, 4, 0, 0x06090011U);
  EXPECT_EQ(u(0x1800, 6), 0U);
}

TEST_F(GatewayDictionary, Od1400h_CobIdMustNotChangeWhileValid) {
  ASSERT_FALSE(w32(0x1400, 1, 0x00000205));
  refused32(0x1400, 1, 0x00000206, 0x06090030U);
  refused32(0x1400, 1, 0x80000206, 0x06090030U);  // invalidating and changing at once
  refused32(0x1400, 1, 0x40000205, 0x06090030U);  // bit 30 too
  EXPECT_FALSE(w32(0x1400, 1, 0x80000205));
  EXPECT_FALSE(w32(0x1400, 1, 0x80000206));
}

TEST_F(GatewayDictionary, Od1800h_CobIdMustNotChangeWhileValid) {
  ASSERT_FALSE(w32(0x1800, 1, 0x00000185));
  refused32(0x1800, 1, 0x40000185, 0x06090030U);  // RTR bit
  refused32(0x1800, 1, 0x00000186, 0x06090030U);
}

TEST_F(GatewayDictionary, Od1400h_RestrictedOr29BitWithoutFrameRejectedOnEnabling) {
  ASSERT_FALSE(w32(0x1400, 1, 0x80000701));
  refused32(0x1400, 1, 0x00000701, 0x06090030U);
  refused32(0x1400, 1, 0x00012345, 0x06090030U);
  EXPECT_FALSE(w32(0x1400, 1, 0x20012345));
}

TEST_F(GatewayDictionary, Od1400h_ReservedTransmissionTypesAreInvalid) {
  for (std::uint64_t t : {0xF1U, 0xFBU, 0xFCU, 0xFDU}) refused8(0x1400, 2, t, 0x06090030U);
  for (std::uint64_t t : {0x00U, 0x01U, 0xF0U, 0xFEU, 0xFFU}) EXPECT_FALSE(w8(0x1400, 2, t)) << t;
}

TEST_F(GatewayDictionary, Od1800h_ReservedTransmissionTypesAreInvalid) {
  for (std::uint64_t t : {0xF1U, 0xF5U, 0xFBU}) refused8(0x1800, 2, t, 0x06090030U);
  for (std::uint64_t t : {0x00U, 0xF0U, 0xFCU, 0xFDU, 0xFEU, 0xFFU}) EXPECT_FALSE(w8(0x1800, 2, t)) << t;
}

TEST_F(GatewayDictionary, Od1400h_TransmissionTypeMustNotChangeWhileValid) {
  ASSERT_FALSE(w32(0x1400, 1, 0x00000205));
  refused8(0x1400, 2, 0x01, 0x06090030U);
  EXPECT_FALSE(w8(0x1400, 2, 0xFE));  // same value
}

TEST_F(GatewayDictionary, Od1800h_InhibitTimeMustNotChangeWhileValid) {
  ASSERT_FALSE(w32(0x1800, 1, 0x00000185));
  refused16(0x1800, 3, 100, 0x06090030U);
  ASSERT_FALSE(w32(0x1800, 1, 0x80000185));
  EXPECT_FALSE(w16(0x1800, 3, 100));
}

TEST_F(GatewayDictionary, Od1800h_SyncStartValueMustNotChangeWhileValid) {
  ASSERT_FALSE(w32(0x1800, 1, 0x00000185));
  refused8(0x1800, 6, 3, 0x06090030U);
}

TEST_F(GatewayDictionary, Od1800h_SyncStartValueAbove240IsTooHigh) {
  refused8(0x1800, 6, 241, 0x06090031U);
  EXPECT_FALSE(w8(0x1800, 6, 240));
}

TEST_F(GatewayDictionary, Od1800h_EventTimerMayChangeWhileValid) {
  ASSERT_FALSE(w32(0x1800, 1, 0x00000185));
  EXPECT_FALSE(w16(0x1800, 5, 500));
  EXPECT_EQ(u(0x1800, 5), 500U);
}

// ---- 7.5.2.36 / 7.5.2.38 PDO mapping -------------------------------------------------------------

TEST_F(GatewayDictionary, Od1600h_1A00h_MappingStartsEmptyWith64Entries) {
  for (std::uint16_t i : Indexes{0x1600, 0x1A00}) {
    EXPECT_EQ(u(i, 0), 0U);
    EXPECT_EQ(od.find(i, 0)->access, Access::ReadWrite);
    EXPECT_NE(od.find(i, 64), nullptr);
    EXPECT_EQ(od.find(i, 65), nullptr);
  }
}

TEST_F(GatewayDictionary, Od1A00h_RemappingProcedureOfTheStandard) {
  add_application_objects();
  ASSERT_FALSE(w32(0x1A00, 1, 0x20000020));  // 2000h sub 0, 32 bits
  ASSERT_FALSE(w32(0x1A00, 2, 0x10010008));  // 1001h sub 0, 8 bits
  ASSERT_FALSE(w8(0x1A00, 0, 2));
  ASSERT_FALSE(w32(0x1800, 1, 0x00000185));  // step 5: create the PDO
  // Steps 1-4 again, with another mapping.
  ASSERT_FALSE(w32(0x1800, 1, 0x80000185));
  ASSERT_FALSE(w8(0x1A00, 0, 0));
  ASSERT_FALSE(w32(0x1A00, 1, 0x20010010));
  ASSERT_FALSE(w8(0x1A00, 0, 1));
  ASSERT_FALSE(w32(0x1800, 1, 0x00000185));
  EXPECT_EQ(u(0x1A00, 0), 1U);
  EXPECT_EQ(u(0x1A00, 1), 0x20010010U);
}

TEST_F(GatewayDictionary, Od1A00h_EntriesChangeOnlyWhileTheCountIsZero) {
  add_application_objects();
  ASSERT_FALSE(w32(0x1A00, 1, 0x20000020));
  ASSERT_FALSE(w8(0x1A00, 0, 1));
  refused32(0x1A00, 2, 0x10010008, 0x06090030U);
  refused32(0x1A00, 1, 0, 0x06090030U);
}

TEST_F(GatewayDictionary, Od1600h_CountMustNotChangeWhileThePdoIsValid) {
  add_application_objects();
  ASSERT_FALSE(w32(0x1600, 1, 0x20000020));
  ASSERT_FALSE(w8(0x1600, 0, 1));
  ASSERT_FALSE(w32(0x1400, 1, 0x00000205));
  refused8(0x1600, 0, 0, 0x06090030U);
  EXPECT_FALSE(w8(0x1600, 0, 1));  // same value
}

TEST_F(GatewayDictionary, Od1A00h_MappedObjectMustExist) {
  refused32(0x1A00, 1, 0x30000008, 0x06020000U);  // no such index
  refused32(0x1A00, 1, 0x10010108, 0x06020000U);  // no such sub-index
}

TEST_F(GatewayDictionary, Od1A00h_MappedObjectMustBeMappable) {
  add_application_objects();
  refused32(0x1A00, 1, 0x10000020, 0x06040041U);  // 1000h is not PDO-mappable
  refused32(0x1A00, 1, 0x20030010, 0x06040041U);
  refused32(0x1A00, 1, 0x20040008, 0x06040041U);  // variable length
}

TEST_F(GatewayDictionary, Od1A00h_MappedLengthMustMatchTheType) {
  add_application_objects();
  refused32(0x1A00, 1, 0x20000010, 0x06040041U);
  refused32(0x1A00, 1, 0x10010010, 0x06040041U);
}

TEST_F(GatewayDictionary, Od1600h_RpdoMapsOnlyWritableObjects) {
  add_application_objects();
  refused32(0x1600, 1, 0x10010008, 0x06040041U);  // 1001h is ro
  refused32(0x1600, 1, 0x20010010, 0x06040041U);  // rwr: TPDO only
  EXPECT_FALSE(w32(0x1600, 1, 0x20020010));       // rww
  EXPECT_FALSE(w32(0x1600, 2, 0x10130020));       // 1013h rw
}

TEST_F(GatewayDictionary, Od1A00h_TpdoMapsOnlyReadableObjects) {
  add_application_objects();
  refused32(0x1A00, 1, 0x20020010, 0x06040041U);  // rww: RPDO only
  EXPECT_FALSE(w32(0x1A00, 1, 0x20010010));       // rwr
  EXPECT_FALSE(w32(0x1A00, 2, 0x10010008));       // ro
}

TEST_F(GatewayDictionary, Od1600h_DummyEntriesOnlyInRpdos) {
  EXPECT_FALSE(w32(0x1600, 1, 0x00050008));  // UNSIGNED8 dummy
  EXPECT_FALSE(w32(0x1600, 2, 0x00070020));  // UNSIGNED32 dummy
  EXPECT_FALSE(w8(0x1600, 0, 2));
  refused32(0x1600, 3, 0x00050010, 0x06090030U);  // count is non-zero now
  ASSERT_FALSE(w8(0x1600, 0, 0));
  refused32(0x1600, 3, 0x00050010, 0x06040041U);  // wrong length
  refused32(0x1600, 3, 0x00080020, 0x06020000U);  // REAL32 is no dummy type
  refused32(0x1A00, 1, 0x00050008, 0x06020000U);
}

TEST_F(GatewayDictionary, Od1A00h_MoreThan64BitsAbortsPdoLengthExceeded) {
  add_application_objects();
  for (std::uint8_t s = 1; s <= 3; ++s) ASSERT_FALSE(w32(0x1A00, s, 0x20000020));
  EXPECT_FALSE(w8(0x1A00, 0, 2));  // exactly 64 bits
  ASSERT_FALSE(w8(0x1A00, 0, 0));
  refused8(0x1A00, 0, 3, 0x06040042U);
}

TEST_F(GatewayDictionary, Od1A00h_EnablingChecksEveryEntryInTheCount) {
  add_application_objects();
  ASSERT_FALSE(w32(0x1A00, 1, 0x20000020));
  refused8(0x1A00, 0, 2, 0x06020000U);  // sub 2 is empty
  ASSERT_FALSE(w32(0x1A00, 2, 0x20010010));
  od.erase(0x2001);
  refused8(0x1A00, 0, 2, 0x06020000U);  // its object went away
}

TEST_F(GatewayDictionary, Od1A00h_CountAbove64IsInvalid) {
  refused8(0x1A00, 0, 0x41, 0x06090030U);
  refused8(0x1A00, 0, 0xFE, 0x06090030U);  // SAM-MPDO: not supported
  refused8(0x1A00, 0, 0xFF, 0x06090030U);  // DAM-MPDO: not supported
}

}  // namespace
}  // namespace canopen::od
