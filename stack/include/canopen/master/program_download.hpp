// Program download (CiA 302-3): replaces the application program of a
// node over SDO, one node-ID at a time per node, many nodes in parallel.
//
// Objects used (CiA 302-3, program download; n = program number 1..254):
//   1F50h sub n  Program data (DOMAIN): the image, written by SDO download.
//   1F51h sub n  Program control (UNSIGNED8): 0 stop, 1 start, 2 reset,
//                3 clear; reading gives the program's state (0 stopped,
//                1 started, 3 no program).
//   1F56h sub n  Program software identification (UNSIGNED32): what the
//                device says identifies the program it holds (for the
//                gateway's simulated devices the CRC-32 of the image).
//   1F57h sub n  Flash status identification (UNSIGNED32): not used here.
//
// Sequence, in this order (ProgramStep):
//   StopProgram        1F51h sub n := 0.
//   ClearProgram       1F51h sub n := 3 (only with options.clear).
//   Download           1F50h sub n := image, Mode::Auto: block transfer for
//                      images above the client's block threshold, falling
//                      back to segmented when the device refuses block
//                      (sdo/client.hpp); progress in bytes.
//   ReadIdentification 1F56h sub n, read BEFORE the start so that
//                      options.expected_identification can keep a wrong
//                      image from being started. An abort NoSuchObject or
//                      NoSuchSubIndex means the device has none: not a
//                      failure (report.identification stays empty).
//   StartProgram       1F51h sub n := 1 (only with options.start).
//   Done               the sequence ended successfully.
// Any failed step ends the sequence (report.step = that step, report.error
// the SDO abort or local error, detail e.g. "clear program (1F51h sub 1 :=
// 3): ..."); the program is then NOT started: no later step runs.
//
// Events: TransferEvent (operation ProgramDownload) through on_event:
// Running at the start and at each step (detail = the step), Running with
// done/total bytes as the SDO client reports download progress
// (ClientConfig::progress_step), then exactly one Done or Failed (error and
// detail as in the report). The Done handler of the run is called after
// that last event.
//
// Sans-I/O: it only drives the SdoClient (timeouts are the client's, per
// transfer options.timeout); the caller MUST keep feeding the client frames
// and time (its completion handlers drive the sequence) and keep the client
// alive as long as this object.
//
// Thread safety: none; use from the SdoClient's thread. Handlers are called
// synchronously from the client's handlers (never from start()) and may
// call back into the downloader.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include "canopen/clock.hpp"
#include "canopen/events.hpp"
#include "canopen/master/transfer_error.hpp"
#include "canopen/sdo/client.hpp"
#include "canopen/types.hpp"

namespace canopen::master {

// CiA 302-3 program control commands (1F51h).
inline constexpr std::uint8_t kProgramStop = 0;
inline constexpr std::uint8_t kProgramStart = 1;
inline constexpr std::uint8_t kProgramReset = 2;
inline constexpr std::uint8_t kProgramClear = 3;
inline constexpr std::uint16_t kProgramData = 0x1F50;
inline constexpr std::uint16_t kProgramControl = 0x1F51;
inline constexpr std::uint16_t kProgramIdentification = 0x1F56;
inline constexpr std::uint16_t kFlashStatus = 0x1F57;

enum class ProgramStep : std::uint8_t { StopProgram, ClearProgram, Download, ReadIdentification, StartProgram, Done };
// "stop program", "clear program", "download", "read identification", "start program", "done".
std::string_view to_string(ProgramStep s);

struct ProgramDownloadOptions {
  std::uint8_t program = 1;  // n: sub-index of 1F50h/1F51h/1F56h, 1..254
  bool clear = true;         // 1F51h := 3 before the download
  bool start = true;         // 1F51h := 1 after it
  // When set, a 1F56h that differs (or is absent) fails at
  // ReadIdentification and the program is not started.
  std::optional<std::uint32_t> expected_identification = std::nullopt;
  // SDO timeout of each transfer (the longest wait for the device's next
  // frame; erasing flash on "clear" may take long); nullopt: the client's.
  std::optional<Duration> timeout = std::nullopt;
};

struct ProgramDownloadReport {
  std::uint8_t node = 0;
  std::uint8_t program = 1;
  ProgramStep step = ProgramStep::Done;  // Done, or the step that failed
  std::error_code error;                 // empty on success
  sdo::Origin origin = sdo::Origin::None;
  std::string detail;
  std::size_t bytes = 0;                          // the image's size
  std::optional<std::uint32_t> identification;    // 1F56h sub n, when the device has it
  bool started = false;                           // 1F51h := 1 was confirmed
  bool cancelled = false;                         // ended by cancel()
  bool ok() const { return !error; }
};

class ProgramDownloader {
 public:
  using EventHandler = std::function<void(const TransferEvent&)>;
  using Done = std::function<void(const ProgramDownloadReport&)>;
  using TimeSource = std::function<TimePoint()>;

  // now: the caller's current time, needed because the next request is
  // submitted from the previous one's completion handler.
  ProgramDownloader(sdo::SdoClient& client, EventHandler on_event, TimeSource now);
  ~ProgramDownloader();  // cancels running sequences without events
  ProgramDownloader(const ProgramDownloader&) = delete;
  ProgramDownloader& operator=(const ProgramDownloader&) = delete;

  // Starts the sequence for `node` (the first request goes out inside this
  // call). Errors (nothing started, no event, done not called):
  // TransferError::BadNode, Busy, BadProgramNumber, EmptyImage, or the SDO
  // client's submit error (e.g. SdoAbort::NoSdoConnection: queue full).
  std::error_code start(std::uint8_t node, ProgramDownloadOptions options, Bytes image, Done done, TimePoint now);
  bool busy(std::uint8_t node) const;
  // Ends a running sequence: its SDO transfer is cancelled, a Failed event
  // and the report (cancelled = true, error SdoAbort::GeneralError) follow.
  // False when none runs.
  bool cancel(std::uint8_t node, TimePoint now);

 private:
  struct Run;
  void submit_step(std::uint8_t node, TimePoint now);
  void advance(std::uint8_t node, TimePoint now);
  void on_done(std::uint8_t node, std::uint64_t gen, sdo::TransferResult&& r);
  void fail(std::uint8_t node, std::error_code ec, sdo::Origin origin, std::string detail, bool cancelled = false);
  void emit(const TransferEvent& ev);
  bool current(std::uint8_t node, std::uint64_t gen) const;

  sdo::SdoClient& client_;
  EventHandler on_event_;
  TimeSource now_;
  std::map<std::uint8_t, Run> runs_;
  std::uint64_t generation_ = 0;
};

}  // namespace canopen::master
