// CiA 302-3 program download (master/program_download.hpp) against a
// simulated device (the demo I/O module's EDS with the simulator's program
// objects 1F50h/1F51h/1F56h/1F57h) over the in-memory bus, fake clock.
#include "canopen/master/program_download.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "canopen/sdo/abort.hpp"
#include "device_rig.hpp"

namespace canopen::master {
namespace {

using namespace std::chrono_literals;
using test::DeviceRig;
constexpr std::uint8_t kNode = DeviceRig::kNode;
constexpr std::uint32_t kTx = 0x600 + kNode;  // SDO client -> server

Bytes image_of(std::size_t n) {
  Bytes b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<std::uint8_t>(i * 7 + (i >> 8));
  return b;
}

struct Download {
  explicit Download(DeviceRig& r) : rig(r), downloader(r.client, [this](const TransferEvent& e) { events.push_back(e); },
                                                        [&r] { return r.clock.now(); }) {}
  std::error_code start(Bytes image, ProgramDownloadOptions o = {}) {
    return downloader.start(kNode, o, std::move(image), [this](const ProgramDownloadReport& r) { report = r; },
                            rig.clock.now());
  }
  // 1F51h sub 1 := 1 frames the master sent (expedited download, 1 byte).
  std::size_t start_frames() const { return rig.count_sent(kTx, {0x2F, 0x51, 0x1F, 0x01, kProgramStart}); }
  std::uint64_t program_state() const {
    auto r = rig.device_od.read(kProgramControl, 1);
    return r ? r.value().at(0) : 0xFF;
  }

  DeviceRig& rig;
  std::vector<TransferEvent> events;
  std::optional<ProgramDownloadReport> report;
  ProgramDownloader downloader;
};

TEST(ProgramDownload, CiA302_3_StopClearBlockDownloadIdentificationStart_ProgressEventsAndCrcIdentification) {
  DeviceRig rig;
  Download d(rig);
  const Bytes image = image_of(20000);
  ASSERT_FALSE(d.start(image));
  EXPECT_TRUE(d.downloader.busy(kNode));
  rig.run_for(2s);

  ASSERT_TRUE(d.report.has_value());
  EXPECT_TRUE(d.report->ok()) << d.report->detail;
  EXPECT_EQ(d.report->step, ProgramStep::Done);
  EXPECT_TRUE(d.report->started);
  EXPECT_EQ(d.report->bytes, image.size());
  ASSERT_TRUE(d.report->identification.has_value());
  EXPECT_EQ(*d.report->identification, sim::program_identification(image)) << "1F56h: CRC-32 of the image";
  EXPECT_FALSE(d.downloader.busy(kNode));

  // The device holds the image and runs it.
  EXPECT_EQ(rig.device_od.get(kProgramData, 1).value().data, ValueData{image});
  EXPECT_EQ(d.program_state(), kProgramStart);
  // Stop, clear and start as 1F51h writes; the image by block download (ccs 6, size and CRC).
  EXPECT_EQ(rig.count_sent(kTx, {0x2F, 0x51, 0x1F, 0x01, kProgramStop}), 1U);
  EXPECT_EQ(rig.count_sent(kTx, {0x2F, 0x51, 0x1F, 0x01, kProgramClear}), 1U);
  EXPECT_EQ(rig.count_sent(kTx, {0xC6, 0x50, 0x1F, 0x01}), 1U);
  EXPECT_EQ(d.start_frames(), 1U);

  // Events: Running from the start, byte progress going up to the total, one Done last.
  ASSERT_GE(d.events.size(), 4U);
  EXPECT_EQ(d.events.front().status, TransferEvent::Status::Running);
  EXPECT_EQ(d.events.front().operation, TransferEvent::Operation::ProgramDownload);
  EXPECT_EQ(d.events.front().total, image.size());
  std::uint64_t last_done = 0;
  std::size_t progress = 0;
  for (std::size_t i = 0; i + 1 < d.events.size(); ++i) {
    EXPECT_EQ(d.events[i].status, TransferEvent::Status::Running);
    EXPECT_GE(d.events[i].done, last_done);
    last_done = d.events[i].done;
    if (d.events[i].done > 0 && d.events[i].done < image.size()) ++progress;
  }
  EXPECT_GE(progress, 3U) << "progress in steps of ClientConfig::progress_step (4096 bytes)";
  EXPECT_EQ(d.events.back().status, TransferEvent::Status::Done);
  EXPECT_EQ(d.events.back().done, image.size());
}

TEST(ProgramDownload, LostBlockSegment_7_2_4_3_9_ResentAfterTheAck_DownloadSucceeds) {
  DeviceRig rig;
  // Drop the 40th frame of the block download's data phase (a segment).
  int segments = -1;
  rig.bus.set_faults({.verdict = [&](const can::Frame& f, std::uint64_t) {
    if (f.id == kTx && f.data[0] == 0xC6 && f.data[1] == 0x50) segments = 0;  // the block initiate
    if (f.id == kTx && segments >= 0 && f.data[0] != 0xC6 && ++segments == 40) return can::FrameVerdict::Drop;
    return can::FrameVerdict::Deliver;
  }});
  Download d(rig);
  const Bytes image = image_of(5000);
  ASSERT_FALSE(d.start(image));
  rig.run_for(3s);
  ASSERT_TRUE(d.report.has_value());
  EXPECT_TRUE(d.report->ok()) << d.report->detail;
  EXPECT_EQ(rig.bus.frames_lost(), 1U);
  EXPECT_EQ(d.report->identification, sim::program_identification(image)) << "the device got every byte";
  EXPECT_TRUE(d.report->started);
}

TEST(ProgramDownload, LostAcknowledgement_FailsAtDownloadWithTimeout_ProgramNotStarted) {
  DeviceRig rig;
  // The device's first sub-block acknowledgement (scs 5, ss 2) never arrives.
  bool dropped = false;
  rig.bus.set_faults({.verdict = [&](const can::Frame& f, std::uint64_t) {
    if (!dropped && f.id == 0x580U + kNode && f.data[0] == 0xA2) {
      dropped = true;
      return can::FrameVerdict::Drop;
    }
    return can::FrameVerdict::Deliver;
  }});
  Download d(rig);
  ASSERT_FALSE(d.start(image_of(3000)));
  rig.run_for(5s);
  ASSERT_TRUE(d.report.has_value());
  EXPECT_EQ(d.report->step, ProgramStep::Download);
  EXPECT_EQ(d.report->error, SdoAbort::Timeout);
  EXPECT_EQ(d.report->origin, sdo::Origin::Local);
  EXPECT_FALSE(d.report->started);
  EXPECT_NE(d.report->detail.find("1F50h sub 1"), std::string::npos) << d.report->detail;
  EXPECT_NE(d.report->detail.find("not started"), std::string::npos) << d.report->detail;
  EXPECT_EQ(d.start_frames(), 0U);
  EXPECT_NE(d.program_state(), kProgramStart);
  ASSERT_FALSE(d.events.empty());
  EXPECT_EQ(d.events.back().status, TransferEvent::Status::Failed);
  EXPECT_EQ(d.events.back().error, SdoAbort::Timeout);
}

TEST(ProgramDownload, DeviceAbortsInTheMiddleOfTheDownload_FailedWithItsCode_NoStartFrame) {
  DeviceRig rig;
  int segments = -1;
  // At the 30th segment the device gives up: abort 08000020h for 1F50h sub 1 (7.2.4.3.17).
  rig.device_filter = [&](const can::Frame& f) {
    if (f.id == kTx && f.data[0] == 0xC6 && f.data[1] == 0x50) segments = 0;
    if (f.id == kTx && segments >= 0 && f.data[0] != 0xC6 && ++segments == 30) {
      rig.device_ep->send(can::Frame::standard(0x580 + kNode, {0x80, 0x50, 0x1F, 0x01, 0x20, 0x00, 0x00, 0x08}));
      return false;
    }
    return true;
  };
  Download d(rig);
  ASSERT_FALSE(d.start(image_of(8000)));
  rig.run_for(3s);
  ASSERT_TRUE(d.report.has_value());
  EXPECT_EQ(d.report->step, ProgramStep::Download);
  EXPECT_EQ(d.report->error, SdoAbort::CannotStore);
  EXPECT_EQ(d.report->origin, sdo::Origin::Remote);
  EXPECT_FALSE(d.report->started);
  EXPECT_EQ(d.start_frames(), 0U);
  EXPECT_NE(d.program_state(), kProgramStart);
  EXPECT_EQ(d.events.back().status, TransferEvent::Status::Failed);
}

TEST(ProgramDownload, DeviceRefusesStop_FailedAtStopProgram_NothingDownloadedNorStarted) {
  DeviceRig rig;
  rig.device_od.find(kProgramControl, 1)->access = od::Access::ReadOnly;  // refuses every 1F51h write
  Download d(rig);
  ASSERT_FALSE(d.start(image_of(1000)));
  rig.run_for(2s);
  ASSERT_TRUE(d.report.has_value());
  EXPECT_EQ(d.report->step, ProgramStep::StopProgram);
  EXPECT_EQ(d.report->error, SdoAbort::WriteOfReadOnly);
  EXPECT_NE(d.report->detail.find("stop program (1F51h sub 1 := 0)"), std::string::npos) << d.report->detail;
  EXPECT_EQ(rig.count_sent(kTx, {0xC6, 0x50, 0x1F}), 0U) << "no download after a failed step";
  EXPECT_EQ(d.start_frames(), 0U);
}

TEST(ProgramDownload, ExpectedIdentificationDiffers_FailedAtReadIdentification_NotStarted) {
  DeviceRig rig;
  Download d(rig);
  const Bytes image = image_of(600);
  ProgramDownloadOptions o;
  o.expected_identification = sim::program_identification(image) ^ 1U;
  ASSERT_FALSE(d.start(image, o));
  rig.run_for(2s);
  ASSERT_TRUE(d.report.has_value());
  EXPECT_EQ(d.report->step, ProgramStep::ReadIdentification);
  EXPECT_EQ(d.report->error, TransferError::WrongIdentification);
  EXPECT_EQ(d.report->identification, sim::program_identification(image));
  EXPECT_EQ(d.start_frames(), 0U);
  EXPECT_EQ(d.program_state(), kProgramStop) << "downloaded, stopped";
}

TEST(ProgramDownload, DeviceWithout1F56h_NoIdentificationIsNoFailure) {
  DeviceRig rig;
  rig.device_od.erase(kProgramIdentification);
  Download d(rig);
  ASSERT_FALSE(d.start(image_of(100)));
  rig.run_for(2s);
  ASSERT_TRUE(d.report.has_value());
  EXPECT_TRUE(d.report->ok()) << d.report->detail;
  EXPECT_FALSE(d.report->identification.has_value());
  EXPECT_TRUE(d.report->started);
}

TEST(ProgramDownload, NoClearNoStart_OnlyStopDownloadAndIdentification) {
  DeviceRig rig;
  Download d(rig);
  ProgramDownloadOptions o;
  o.clear = false;
  o.start = false;
  ASSERT_FALSE(d.start(image_of(100), o));
  rig.run_for(2s);
  ASSERT_TRUE(d.report.has_value());
  EXPECT_TRUE(d.report->ok());
  EXPECT_FALSE(d.report->started);
  EXPECT_EQ(rig.count_sent(kTx, {0x2F, 0x51, 0x1F, 0x01, kProgramClear}), 0U);
  EXPECT_EQ(d.start_frames(), 0U);
  EXPECT_EQ(d.program_state(), kProgramStop);
}

TEST(ProgramDownload, StartErrors_BadNodeProgramEmptyImageBusy_NothingSent) {
  DeviceRig rig;
  Download d(rig);
  ProgramDownloadOptions o;
  EXPECT_EQ(d.downloader.start(0, o, image_of(10), nullptr, rig.clock.now()), TransferError::BadNode);
  EXPECT_EQ(d.downloader.start(128, o, image_of(10), nullptr, rig.clock.now()), TransferError::BadNode);
  o.program = 0;
  EXPECT_EQ(d.start(image_of(10), o), TransferError::BadProgramNumber);
  o.program = 255;
  EXPECT_EQ(d.start(image_of(10), o), TransferError::BadProgramNumber);
  EXPECT_EQ(d.start(Bytes{}), TransferError::EmptyImage);
  EXPECT_TRUE(rig.master_frames.empty());
  EXPECT_TRUE(d.events.empty());
  ASSERT_FALSE(d.start(image_of(10)));
  EXPECT_EQ(d.start(image_of(10)), TransferError::Busy);
  rig.run_for(2s);
  EXPECT_TRUE(d.report && d.report->ok());
}

TEST(ProgramDownload, Cancel_FailedEventAndReportCancelled_NotStarted) {
  DeviceRig rig;
  rig.device_filter = [](const can::Frame&) { return false; };  // a silent device
  Download d(rig);
  ASSERT_FALSE(d.start(image_of(100)));
  EXPECT_TRUE(d.downloader.cancel(kNode, rig.clock.now()));
  ASSERT_TRUE(d.report.has_value());
  EXPECT_TRUE(d.report->cancelled);
  EXPECT_EQ(d.report->step, ProgramStep::StopProgram);
  EXPECT_EQ(d.events.back().status, TransferEvent::Status::Failed);
  EXPECT_FALSE(d.downloader.busy(kNode));
  EXPECT_FALSE(d.downloader.cancel(kNode, rig.clock.now()));
}

}  // namespace
}  // namespace canopen::master
