// DCF read-back and apply (master/dcf_transfer.hpp) against a simulated
// device (the demo I/O module's EDS on a canopen::Device) over the
// in-memory bus, fake clock; write_dcf() round trips through the EDS/DCF
// reader (CiA 306), also for the vendor corpus in ../shared/eds-corpus.
#include "canopen/master/dcf_transfer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <set>
#include <vector>

#include "canopen/sdo/abort.hpp"
#include "device_rig.hpp"

namespace canopen::master {
namespace {

using namespace std::chrono_literals;
using test::DeviceRig;
constexpr std::uint8_t kNode = DeviceRig::kNode;
constexpr std::uint32_t kTx = 0x600 + kNode;

Value u8(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned8, v); }
Value u16(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned16, v); }
Value u32(std::uint64_t v) { return Value::of_unsigned(DataType::Unsigned32, v); }

bool contains(const std::vector<ObjectAddress>& v, std::uint16_t index, std::uint8_t sub) {
  return std::find(v.begin(), v.end(), ObjectAddress{index, sub}) != v.end();
}

// A device that drifted from its EDS: other heartbeat, filter time, name,
// calibration bytes and TPDO1 mapping.
void drift(DeviceRig& rig) {
  auto& od = rig.device_od;
  ASSERT_FALSE(od.set(0x1017, 0, u16(250)));
  ASSERT_FALSE(od.set(0x2002, 0, u16(33)));
  ASSERT_FALSE(od.set(0x2001, 0, Value::of_string("cabinet 4, left")));
  ASSERT_FALSE(od.set(0x2004, 0, Value::of_bytes(DataType::OctetString, {0xDE, 0xAD, 0x00, 0x01})));
  ASSERT_FALSE(od.set(0x1A00, 0, u8(2)));
  ASSERT_FALSE(od.set(0x1A00, 2, u32(0x64010110)));
}

struct Reader {
  explicit Reader(DeviceRig& r)
      : rig(r), reader(r.client, [this](const TransferEvent& e) { events.push_back(e); }, [&r] { return r.clock.now(); }) {}
  std::error_code start(const eds::DeviceDescription& d) {
    return reader.start(kNode, d, [this](const DcfReadReport& r) { report = r; }, rig.clock.now());
  }
  DeviceRig& rig;
  std::vector<TransferEvent> events;
  std::optional<DcfReadReport> report;
  DcfReader reader;
};

struct Applier {
  explicit Applier(DeviceRig& r)
      : rig(r),
        applier(
            r.client,
            [this](NmtCommand cs, std::uint8_t node) {
              nmt.push_back(cs);
              rig.master_ep->send(can::Frame::standard(0x000, {static_cast<std::uint8_t>(cs), node}));
            },
            [this](const TransferEvent& e) { events.push_back(e); }, [&r] { return r.clock.now(); }) {}
  std::error_code start(const eds::DeviceDescription& dcf, DcfApplyOptions o = {}) {
    return applier.start(kNode, dcf, o, [this](const DcfApplyReport& r) { report = r; }, rig.clock.now());
  }
  DeviceRig& rig;
  std::vector<TransferEvent> events;
  std::vector<NmtCommand> nmt;
  std::optional<DcfApplyReport> report;
  DcfApplier applier;
};

// ---- which objects (CiA 301 7.5 areas, CiA 306 ObjFlags) -------------------------------

TEST(DcfObjects, CommunicationAreaReadWriteAndUnmappableApplicationParameters) {
  DeviceRig rig;
  auto objects = configurable_objects(rig.eds);
  EXPECT_TRUE(contains(objects, 0x1017, 0));
  EXPECT_TRUE(contains(objects, 0x1400, 1)) << "PDO communication parameters";
  EXPECT_TRUE(contains(objects, 0x1A00, 0)) << "PDO mapping parameters";
  EXPECT_TRUE(contains(objects, 0x1A00, 4));
  EXPECT_TRUE(contains(objects, 0x2001, 0)) << "application parameter, VISIBLE_STRING";
  EXPECT_TRUE(contains(objects, 0x6424, 1));
  EXPECT_FALSE(contains(objects, 0x1000, 0)) << "read-only";
  EXPECT_FALSE(contains(objects, 0x1018, 1)) << "read-only";
  EXPECT_FALSE(contains(objects, 0x1003, 0)) << "history: writing 0 clears it";
  EXPECT_FALSE(contains(objects, 0x1010, 1)) << "store command";
  EXPECT_FALSE(contains(objects, 0x1011, 1)) << "restore command";
  EXPECT_FALSE(contains(objects, 0x1F51, 1)) << "CiA 302-3 program control";
  EXPECT_FALSE(contains(objects, 0x2000, 0)) << "DOMAIN";
  EXPECT_FALSE(contains(objects, 0x6200, 1)) << "PDO-mappable: process data";
  EXPECT_FALSE(contains(objects, 0x6000, 1)) << "read-only input";
  // CiA 306 ObjFlags bit 1: refuse read on scan.
  rig.eds.entry_facts[0x2002U << 8].obj_flags = eds::kObjFlagRefuseReadOnScan;
  objects = configurable_objects(rig.eds);
  EXPECT_FALSE(contains(objects, 0x2002, 0));
}

// ---- read-back ----------------------------------------------------------------

TEST(DcfRead, ReadBackEqualsTheDevicesDictionary_EveryConfigurableObject) {
  DeviceRig rig;
  drift(rig);
  Reader r(rig);
  ASSERT_FALSE(r.start(rig.eds));
  rig.run_for(5s);
  ASSERT_TRUE(r.report.has_value());
  EXPECT_FALSE(r.report->stopped) << r.report->detail;
  EXPECT_TRUE(r.report->failed.empty()) << r.report->failed.front().detail;
  const auto objects = configurable_objects(rig.eds);
  EXPECT_EQ(r.report->total, objects.size());
  ASSERT_EQ(r.report->values.size(), objects.size());
  for (const auto& a : objects) {
    const auto want = rig.device_od.get(a.index, a.sub);
    ASSERT_TRUE(want.ok());
    EXPECT_EQ(r.report->values.at(a), want.value()) << od::object_label(a.index, a.sub);
  }
  EXPECT_EQ(r.report->values.at({0x2001, 0}), Value::of_string("cabinet 4, left"));
  // Running (total), one per object, Done last with done == total.
  EXPECT_EQ(r.events.front().status, TransferEvent::Status::Running);
  EXPECT_EQ(r.events.front().operation, TransferEvent::Operation::DcfRead);
  EXPECT_EQ(r.events.front().total, objects.size());
  EXPECT_EQ(r.events.size(), objects.size() + 1);
  EXPECT_EQ(r.events.back().status, TransferEvent::Status::Done);
  EXPECT_EQ(r.events.back().done, objects.size());
  // One at a time, normal uploads for fixed-size types (no block initiates).
  EXPECT_EQ(rig.count_sent(kTx, {0xA0}), 0U);
}

TEST(DcfRead, ObjectsThatAbortAreListed_TheReadGoesOn) {
  DeviceRig rig;
  rig.device_od.erase(0x2002);
  rig.device_od.find(0x6424, 3)->access = od::Access::WriteOnly;
  Reader r(rig);
  ASSERT_FALSE(r.start(rig.eds));
  rig.run_for(5s);
  ASSERT_TRUE(r.report.has_value());
  EXPECT_FALSE(r.report->stopped);
  ASSERT_EQ(r.report->failed.size(), 2U);
  EXPECT_EQ(r.report->failed[0].index, 0x2002);
  EXPECT_EQ(r.report->failed[0].error, SdoAbort::NoSuchObject);
  EXPECT_EQ(r.report->failed[0].origin, sdo::Origin::Remote);
  EXPECT_EQ(r.report->failed[1].index, 0x6424);
  EXPECT_EQ(r.report->failed[1].sub, 3);
  EXPECT_EQ(r.report->failed[1].error, SdoAbort::ReadOfWriteOnly);
  EXPECT_EQ(r.report->values.size(), r.report->total - 2);
  EXPECT_TRUE(r.report->values.contains({0x6425, 4})) << "objects after the aborts were read";
  EXPECT_EQ(r.events.back().status, TransferEvent::Status::Done) << "aborts are not a failure";
}

TEST(DcfRead, SilentNode_TimeoutEndsTheReadEarly_Failed) {
  DeviceRig rig;
  rig.device_filter = [](const can::Frame&) { return false; };
  Reader r(rig);
  ASSERT_FALSE(r.start(rig.eds));
  rig.run_for(5s);
  ASSERT_TRUE(r.report.has_value());
  EXPECT_EQ(r.report->stopped, SdoAbort::Timeout);
  EXPECT_TRUE(r.report->values.empty());
  EXPECT_EQ(rig.count_sent(kTx, {0x40}), 1U) << "one timeout, not one per object";
  EXPECT_EQ(r.events.back().status, TransferEvent::Status::Failed);
  EXPECT_EQ(r.events.back().error, SdoAbort::Timeout);
}

TEST(DcfRead, StartErrors) {
  DeviceRig rig;
  Reader r(rig);
  EXPECT_EQ(r.reader.start(0, rig.eds, nullptr, rig.clock.now()), TransferError::BadNode);
  eds::DeviceDescription empty;
  EXPECT_EQ(r.start(empty), TransferError::NothingToTransfer);
  ASSERT_FALSE(r.start(rig.eds));
  EXPECT_EQ(r.start(rig.eds), TransferError::Busy);
  EXPECT_TRUE(r.reader.cancel(kNode, rig.clock.now()));
  ASSERT_TRUE(r.report.has_value());
  EXPECT_TRUE(r.report->cancelled);
}

// ---- write_dcf (CiA 306) ----------------------------------------------------------

TEST(WriteDcf, RoundTripThroughTheReader_SameValuesNoWarnings) {
  DeviceRig rig;
  drift(rig);
  Reader r(rig);
  ASSERT_FALSE(r.start(rig.eds));
  rig.run_for(5s);
  ASSERT_TRUE(r.report.has_value());
  const std::string text = write_dcf(rig.eds, kNode, r.report->values);

  // No node-ID given: the DCF's [DeviceComissioning] NodeID is the one.
  const eds::DeviceDescription back = eds::parse_device_description(text, "node5.dcf");
  EXPECT_TRUE(back.warnings.empty()) << back.warnings.front();
  EXPECT_TRUE(back.is_dcf);
  EXPECT_EQ(back.node_id, kNode);
  EXPECT_EQ(back.device.product_name, rig.eds.device.product_name);
  EXPECT_EQ(back.device.vendor_number, rig.eds.device.vendor_number);
  EXPECT_EQ(back.file.last_eds, rig.eds.file.file_name);
  for (const auto& [a, v] : r.report->values) {
    const od::SubEntry* e = back.od.find(a.index, a.sub);
    ASSERT_NE(e, nullptr) << od::object_label(a.index, a.sub);
    EXPECT_EQ(e->value, v) << od::object_label(a.index, a.sub);
    EXPECT_TRUE(back.facts(a.index, a.sub).parameter_value);
    EXPECT_EQ(e->default_value, rig.eds.od.find(a.index, a.sub)->default_value) << "DefaultValue kept";
  }
  // Every object of the EDS is described; non-configurable ones carry no ParameterValue.
  EXPECT_EQ(back.od.objects().size(), rig.eds.od.objects().size());
  EXPECT_FALSE(back.facts(0x1018, 1).parameter_value);
  // The EDS's number conventions: its COB-IDs are hex ($NODEID+0x180), its heartbeat decimal.
  EXPECT_NE(text.find("ParameterValue=0x185\n"), std::string::npos);
  EXPECT_NE(text.find("ParameterValue=250\n"), std::string::npos);
}

TEST(WriteDcf, VendorCorpus_EveryReadableFileRoundTripsItsConfigurableValues) {
  const auto corpus = std::filesystem::path(CANOPEN_SOURCE_DIR) / ".." / "shared" / "eds-corpus";
  if (!std::filesystem::is_directory(corpus)) GTEST_SKIP() << corpus << " not found";
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(corpus)) {
    const auto ext = entry.path().extension().string();
    if (!entry.is_regular_file() || (ext != ".eds" && ext != ".dcf" && ext != ".EDS" && ext != ".DCF")) continue;
    eds::DeviceDescription d;
    try {
      d = eds::load_device_description(entry.path(), kNode);
    } catch (const eds::EdsError&) {
      continue;  // refused files are the reader's tests
    }
    std::map<ObjectAddress, Value> values;
    for (const auto& a : configurable_objects(d)) values.emplace(a, d.od.find(a.index, a.sub)->value);
    const std::string text = write_dcf(d, kNode, values);
    eds::DeviceDescription back;
    try {
      back = eds::parse_device_description(text, "node5.dcf");
    } catch (const eds::EdsError& e) {
      ADD_FAILURE() << entry.path() << ": the DCF written is refused: " << e.what();
      continue;
    }
    ++files;
    for (const auto& [a, v] : values) {
      const od::SubEntry* e = back.od.find(a.index, a.sub);
      ASSERT_NE(e, nullptr) << entry.path() << " " << od::object_label(a.index, a.sub);
      EXPECT_EQ(e->value, v) << entry.path() << " " << od::object_label(a.index, a.sub);
    }
  }
  EXPECT_GE(files, 200U);
}

// ---- apply ------------------------------------------------------------------------

// What C does with a DCF posted: parse it, apply it.
eds::DeviceDescription dcf_of(const DeviceRig& rig, const std::map<ObjectAddress, Value>& values) {
  return eds::parse_device_description(write_dcf(rig.eds, kNode, values), "node5.dcf");
}

std::map<ObjectAddress, Value> eds_values(const DeviceRig& rig) {
  std::map<ObjectAddress, Value> values;
  for (const auto& a : configurable_objects(rig.eds)) values.emplace(a, rig.eds.od.find(a.index, a.sub)->value);
  return values;
}

TEST(PlanAllValues, EveryParameterValueWritten_EvenDefaults_NotRefuseWriteNorEntriesWithout) {
  DeviceRig rig;
  auto values = eds_values(rig);
  values.erase({0x2002, 0});
  eds::DeviceDescription dcf = dcf_of(rig, values);
  dcf.entry_facts[0x2005U << 8].obj_flags = eds::kObjFlagRefuseWriteOnDownload;
  const auto plan = plan_configuration(dcf, PlanScope::AllValues);
  auto has = [&](std::uint16_t i, std::uint8_t s) {
    return std::any_of(plan.begin(), plan.end(), [&](const ConfigWrite& w) { return w.index == i && w.sub == s; });
  };
  EXPECT_TRUE(has(0x1006, 0)) << "equal to its default, still written";
  EXPECT_TRUE(has(0x2001, 0));
  EXPECT_FALSE(has(0x2002, 0)) << "no ParameterValue";
  EXPECT_FALSE(has(0x2005, 0)) << "ObjFlags bit 0: refuse write on download";
  EXPECT_FALSE(has(0x1010, 1));
  EXPECT_FALSE(has(0x1F51, 1));
  // The boot-up plan of the same DCF writes only what differs (and 1017h).
  const auto boot_plan = plan_configuration(dcf);  // one vector: begin and end of the same one
  EXPECT_FALSE(std::any_of(boot_plan.begin(), boot_plan.end(), [](const ConfigWrite& w) { return w.index == 0x1006; }));
}

// 7.5.2.35/36 remapping order, frame by frame as the boot configurator:
// COB-ID read, COB-ID with bit 31, other communication subs, count 0,
// entries, count, COB-ID as in the DCF.
TEST(DcfApply, FramesInTheBootConfiguratorsOrder_PdoDisabledBeforeRemapping) {
  DeviceRig rig;
  auto values = eds_values(rig);
  values[{0x1A00, 0}] = u8(2);
  values[{0x1A00, 2}] = u32(0x64010110);
  values[{0x1017, 0}] = u16(500);
  const eds::DeviceDescription dcf = dcf_of(rig, values);
  // The plan's order; a PDO's COB-ID is read first and only written with
  // bit 31 where the device has the PDO valid (boot configurator rule).
  std::vector<std::string> want;
  auto initiate = [](bool upload, std::uint16_t index, std::uint8_t sub) {
    return (upload ? "U" : "D") + od::object_label(index, sub);
  };
  for (const auto& w : plan_configuration(dcf, PlanScope::AllValues)) {
    if (w.invalidate) {
      want.push_back(initiate(true, w.index, w.sub));
      if ((rig.device_od.get_unsigned(w.index, w.sub).value_or(0) & 0x80000000U) != 0) continue;
    }
    want.push_back(initiate(false, w.index, w.sub));
  }
  Applier a(rig);
  ASSERT_FALSE(a.start(dcf));
  rig.run_for(5s);
  ASSERT_TRUE(a.report.has_value());
  EXPECT_FALSE(a.report->stopped) << a.report->detail;
  EXPECT_EQ(a.report->failed, 0U);

  // Initiates the master sent, in order: "U1800h sub 1" (upload), "D1800h sub 1" (download).
  using Initiate = std::string;
  std::vector<Initiate> sent;
  std::optional<Bytes> first_cob, last_cob;
  for (const auto& f : rig.master_frames) {
    if (f.id != kTx) continue;
    const std::uint8_t ccs = f.data[0] >> 5;
    if (ccs != 1 && ccs != 2) continue;  // initiate download / upload only
    const auto index = static_cast<std::uint16_t>(f.data[1] | f.data[2] << 8);
    sent.push_back(initiate(ccs == 2, index, f.data[3]));
    if (ccs == 1 && index == 0x1800 && f.data[3] == 1) {
      Bytes b(f.data.begin() + 4, f.data.begin() + 8);
      (first_cob ? last_cob : first_cob) = b;
    }
  }
  EXPECT_EQ(sent, want);
  // TPDO1 of the I/O module, whole, before TPDO2: 1800h sub 1 disabled, its
  // other subs, 1A00h sub 0 = 0, subs 1-2, sub 0 = 2, 1800h sub 1 again.
  const auto first = std::find(sent.begin(), sent.end(), initiate(true, 0x1800, 1));
  ASSERT_NE(first, sent.end());
  EXPECT_EQ(std::vector<Initiate>(first, first + 11),
            (std::vector<Initiate>{initiate(true, 0x1800, 1), initiate(false, 0x1800, 1), initiate(false, 0x1800, 2),
                                   initiate(false, 0x1800, 3), initiate(false, 0x1800, 5), initiate(false, 0x1A00, 0),
                                   initiate(false, 0x1A00, 1), initiate(false, 0x1A00, 2), initiate(false, 0x1A00, 0),
                                   initiate(false, 0x1800, 1), initiate(true, 0x1801, 1)}));
  ASSERT_TRUE(first_cob && last_cob);
  EXPECT_EQ(*first_cob, encode(u32(0x80000185))) << "disabled first (bit 31), bits 0-29 kept";
  EXPECT_EQ(*last_cob, encode(u32(0x185)));
  // The device holds the DCF's values.
  EXPECT_EQ(rig.device_od.get_unsigned(0x1A00, 0), 2U);
  EXPECT_EQ(rig.device_od.get_unsigned(0x1A00, 2), 0x64010110U);
  EXPECT_EQ(rig.device_od.get_unsigned(0x1017, 0), 500U);
  EXPECT_EQ(a.report->objects.size(), a.report->total);
  EXPECT_EQ(a.events.back().status, TransferEvent::Status::Done);
  EXPECT_EQ(a.events.back().done, a.report->total);
}

TEST(DcfApply, OneAbortInTheMiddle_OneOutcomePerObject_TheRestWritten) {
  DeviceRig rig;
  auto values = eds_values(rig);
  values[{0x2002, 0}] = u16(44);
  const DataType limit_type = rig.eds.od.find(0x6425, 4)->type;
  values[{0x6425, 4}] = Value::of_signed(limit_type, -77);
  rig.device_od.find(0x2002, 0)->access = od::Access::ReadOnly;  // this device refuses it
  Applier a(rig);
  ASSERT_FALSE(a.start(dcf_of(rig, values)));
  rig.run_for(5s);
  ASSERT_TRUE(a.report.has_value());
  EXPECT_FALSE(a.report->stopped);
  ASSERT_EQ(a.report->objects.size(), a.report->total);
  EXPECT_EQ(a.report->failed, 1U);
  for (const auto& o : a.report->objects) {
    if (o.index == 0x2002) {
      EXPECT_EQ(o.error, SdoAbort::WriteOfReadOnly);
      EXPECT_EQ(o.origin, sdo::Origin::Remote);
      EXPECT_FALSE(o.detail.empty());
    } else {
      EXPECT_FALSE(o.error) << od::object_label(o.index, o.sub) << ": " << o.detail;
    }
  }
  EXPECT_EQ(rig.device_od.get(0x6425, 4).value(), Value::of_signed(limit_type, -77)) << "written after the abort";
  EXPECT_EQ(a.events.back().status, TransferEvent::Status::Done);
  EXPECT_NE(a.events.back().detail.find("1 refused"), std::string::npos) << a.events.back().detail;
}

// CiA 301 7.5.2.13: "save" makes the written values the ones the device
// comes back with after a reset node.
TEST(DcfApply, StoreThenResetNode_ValuesSurviveTheReset) {
  DeviceRig rig;
  auto values = eds_values(rig);
  values[{0x2002, 0}] = u16(45);
  values[{0x1017, 0}] = u16(700);
  Applier a(rig);
  DcfApplyOptions o;
  o.store = true;
  o.reset = true;
  ASSERT_FALSE(a.start(dcf_of(rig, values), o));
  rig.run_for(5s);
  ASSERT_TRUE(a.report.has_value());
  EXPECT_TRUE(a.report->stored);
  EXPECT_TRUE(a.report->reset);
  EXPECT_EQ(a.nmt, std::vector<NmtCommand>{NmtCommand::ResetNode});
  EXPECT_EQ(rig.count_sent(kTx, {0x23, 0x10, 0x10, 0x01, 's', 'a', 'v', 'e'}), 1U);
  EXPECT_EQ(rig.device->state(), NmtState::PreOperational) << "booted again";
  EXPECT_EQ(rig.device_od.get_unsigned(0x2002, 0), 45U);
  EXPECT_EQ(rig.device_od.get_unsigned(0x1017, 0), 700U);
}

TEST(DcfApply, WithoutStore_ResetNodeBringsThePowerOnValuesBack) {
  DeviceRig rig;
  auto values = eds_values(rig);
  values[{0x2002, 0}] = u16(46);
  Applier a(rig);
  DcfApplyOptions o;
  o.reset = true;
  ASSERT_FALSE(a.start(dcf_of(rig, values), o));
  rig.run_for(5s);
  ASSERT_TRUE(a.report.has_value());
  EXPECT_FALSE(a.report->stored);
  EXPECT_TRUE(a.report->reset);
  EXPECT_EQ(rig.device_od.get(0x2002, 0).value(), rig.eds.od.find(0x2002, 0)->value);
}

TEST(DcfApply, SaveRefused_NoReset_StoreErrorReported) {
  DeviceRig rig;
  rig.device_od.erase(0x1010);
  Applier a(rig);
  DcfApplyOptions o;
  o.store = true;
  o.reset = true;
  ASSERT_FALSE(a.start(dcf_of(rig, eds_values(rig)), o));
  rig.run_for(5s);
  ASSERT_TRUE(a.report.has_value());
  EXPECT_FALSE(a.report->stored);
  ASSERT_TRUE(a.report->store_error.has_value());
  EXPECT_EQ(a.report->store_error->error, SdoAbort::NoSuchObject);
  EXPECT_FALSE(a.report->reset) << "a reset would throw the written values away";
  EXPECT_TRUE(a.nmt.empty());
}

TEST(DcfApply, SilentNode_TimeoutEndsTheApplyEarly_Failed) {
  DeviceRig rig;
  rig.device_filter = [](const can::Frame&) { return false; };
  Applier a(rig);
  ASSERT_FALSE(a.start(dcf_of(rig, eds_values(rig)), {.store = true, .reset = true}));
  rig.run_for(5s);
  ASSERT_TRUE(a.report.has_value());
  EXPECT_EQ(a.report->stopped, SdoAbort::Timeout);
  EXPECT_FALSE(a.report->reset);
  EXPECT_TRUE(a.nmt.empty());
  EXPECT_EQ(a.events.back().status, TransferEvent::Status::Failed);
}

TEST(DcfApply, StartErrors) {
  DeviceRig rig;
  Applier a(rig);
  EXPECT_EQ(a.applier.start(128, rig.eds, {}, nullptr, rig.clock.now()), TransferError::BadNode);
  // An EDS without ParameterValues has nothing to apply.
  EXPECT_EQ(a.start(rig.eds), TransferError::NothingToTransfer);
  ASSERT_FALSE(a.start(dcf_of(rig, eds_values(rig))));
  EXPECT_EQ(a.start(dcf_of(rig, eds_values(rig))), TransferError::Busy);
}

}  // namespace
}  // namespace canopen::master
