// One CAN network seen from the gateway (the NMT master side): the services
// that watch and talk to the other nodes, fed as one sans-I/O unit, and one
// ordered event stream in which every event carries a per-network sequence
// number (+1 per event, so a consumer sees gaps) and a timestamp: the
// receive time of the frame that caused it, or the wall time for events a
// timer caused (a node lost).
//
// Services: NMT master (node tracking, heartbeat consumer, node guarding),
// SDO client, boot-up configuration of nodes (CiA 302 spirit), DCF
// read-back and apply, program download (CiA 302-3), PDO receiver
// (the nodes' TPDOs), PDO producer (process data to the nodes' RPDOs, with
// synchronous types driven by the SYNCs this network sees), EMCY, SYNC and
// TIME consumers, LSS master (CiA 305).
//
// A 1017h (producer heartbeat time) this network's SDO client writes to a
// node, whoever asked for it, is the period the node is watched with from
// then on (NmtMaster::set_producer_time()).
//
// PDOs follow the devices (CiA 301 7.2.2, 7.5.2.35-7.5.2.39): every
// successful SDO download by this network's SDO client to 1400h-1BFFh of a
// described node - whoever asked for it, boot-up DCF included - changes
// that PDO's COB-ID, transmission type or mapping in the decoder (TPDOs)
// and producer (RPDOs) before the download's completion handler runs; the
// node's PDO configuration can also be read back from the device
// (read_pdo_config(), or at each boot-up). A boot-up alone changes nothing
// here: whether the device kept what was written (stored) or went back to
// its defaults is only known by reading. See pdo/remote_config.hpp.
//
// The caller MUST pass every received frame to on_frame(), call on_time()
// when now >= next_deadline() (re-read after those two calls), and pass bus
// events to report(). Calls from outside that move the deadline - through
// nmt(), sdo(), rpdo(), read_pdo_config(), add_node(), ... - report it to
// the on_deadline_change() observer (canopen/deadline.hpp). Not thread-safe; handlers run synchronously inside
// those calls.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <system_error>
#include <vector>

#include "canopen/deadline.hpp"
#include "canopen/emcy/emcy.hpp"
#include "canopen/sync/sync.hpp"
#include "canopen/time/time.hpp"
#include "canopen/events.hpp"
#include "canopen/lss/master.hpp"
#include "canopen/master/boot_configurator.hpp"
#include "canopen/master/dcf_transfer.hpp"
#include "canopen/master/program_download.hpp"
#include "canopen/nmt/master.hpp"
#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/config_reader.hpp"
#include "canopen/pdo/receiver.hpp"
#include "canopen/pdo/remote_config.hpp"
#include "canopen/pdo/transmitter.hpp"
#include "canopen/sdo/client.hpp"

namespace canopen {

class Network : public DeadlineSource {
 public:
  using FrameSink = std::function<void(const can::Frame&)>;
  using EventHandler = std::function<void(const Event&)>;
  using WallClock = std::function<can::Frame::Clock::time_point()>;

  // own: the gateway's dictionary on this network (1016h heartbeat
  // consumers, 1007h SYNC window, 1012h TIME); it must outlive the network.
  Network(const od::ObjectDictionary& own, FrameSink sink, EventHandler on_event, sdo::ClientConfig sdo_config = {},
          WallClock wall = [] { return can::Frame::Clock::now(); });
  Network(const Network&) = delete;
  Network& operator=(const Network&) = delete;

  // Describes a remote node (its EDS/DCF dictionary, copied): its TPDOs are
  // decoded and its RPDOs can be written through rpdo(). Replaces an earlier
  // description of the node as a whole (PDOs the new one lacks are no longer
  // decoded or produced; what was read from the device is forgotten).
  // Returns problems that leave parts undecodable.
  std::vector<std::string> add_node(std::uint8_t node, const od::ObjectDictionary& description);
  // Forgets a node's description and boot-up configuration (run-time
  // configuration): its TPDOs are reported raw again, its RPDOs no longer
  // produced, a running PDO read ends cancelled (PdoReadReport::cancelled)
  // and a running boot-up sequence is dropped without an event. Watching
  // (nmt()) is not touched.
  void remove_node(std::uint8_t node);
  // Boot-up configuration of `node` (master/boot_configurator.hpp): on each boot-up its
  // identity is checked, its DCF written and it is started, as `config`
  // says; every step is a BootConfigEvent in this network's stream.
  // config.dcf MUST outlive the network. A configured node heard first by
  // its heartbeat or guarding (powered before the gateway), or back after a
  // loss in another state, gets the same sequence without its boot-up:
  // pre-operational the whole of it, operational the identity check and PDO
  // read only, never a restart (BootConfigurator::on_found()). With read_pdo_config, after the
  // identity check and DCF download and before the NMT start (so no TPDO
  // is decoded with a mapping the device does not use) the node's PDO
  // configuration is read as read_pdo_config() does; the Start and Done
  // events follow the read, Done's detail summing it up. Aborts for single
  // PDOs keep the earlier configuration of those PDOs and do not stop the
  // boot; a local error (timeout) is Failed, as for any other step.
  bool configure_boot(std::uint8_t node, master::NodeBootConfig config, bool read_pdo_config = false);
  // Reads the PDO configuration of a node added with add_node() from the
  // device by SDO (pdo/config_reader.hpp): every PDO its description has,
  // plus any created by writes. What was read replaces what was in effect
  // (source Device), the decoder and producer follow, then `done` gets the
  // report. A read already running for the node is joined. Errors (done
  // not called): SdoAbort::NoSuchObject for a node not added, the SDO
  // client's submit errors. A boot-up of the node cancels its read.
  std::error_code read_pdo_config(std::uint8_t node, pdo::PdoConfigReader::Done done, TimePoint now);
  // ---- maintenance transfers (one at a time per node, any kind) ------------
  // Each runs its service (master/dcf_transfer.hpp, master/program_download.hpp)
  // on this network's SdoClient, through the node's SDO queue, and reports
  // TransferEvents in this network's event stream (seq, wall-time stamp):
  // Running at the start and with progress, then one Done or Failed; `done`
  // is called after that last event. Errors returned (nothing started, no
  // event, done not called): master::TransferError::BadNode (not 1..127),
  // Busy (a DCF read, DCF apply or program download already runs for the
  // node: REST 409), NothingToTransfer, BadProgramNumber, EmptyImage, or
  // the SDO client's submit error (SdoAbort::NoSdoConnection: queue full).
  // The descriptions are not kept after the call. A boot-up of the node
  // does not cancel them (an SDO timeout does); cancel_transfer() does.
  //
  // Reads the configurable objects of `description` (the node's EDS/DCF)
  // from the node; master::write_dcf(description, node, report.values)
  // makes the DCF text.
  std::error_code read_dcf(std::uint8_t node, const eds::DeviceDescription& description,
                           master::DcfReader::Done done, TimePoint now);
  // Writes the values of `dcf` to the node (PDO writes update the decoder
  // and producer as any SDO download to 1400h-1BFFh does), then optionally
  // stores (1010h sub 1 "save") and resets it (NMT reset node).
  std::error_code apply_dcf(std::uint8_t node, const eds::DeviceDescription& dcf, master::DcfApplyOptions options,
                            master::DcfApplier::Done done, TimePoint now);
  // CiA 302-3 program download of `image` to program options.program.
  std::error_code download_program(std::uint8_t node, master::ProgramDownloadOptions options, Bytes image,
                                   master::ProgramDownloader::Done done, TimePoint now);
  // Whether a DCF read, DCF apply or program download runs for the node.
  bool transfer_busy(std::uint8_t node) const;
  // Cancels the node's running transfer (Failed event, done with
  // cancelled = true); false when none runs.
  bool cancel_transfer(std::uint8_t node, TimePoint now);

  // The PDO parameters in effect for the described nodes and their source.
  const pdo::RemotePdoTable& pdo_config() const { return pdo_table_; }
  // Sends an NMT command (node 0 = all) and, for start/stop/pre-operational,
  // nothing else; the nodes' heartbeats report the result.
  bool send_nmt(NmtCommand command, std::uint8_t node) { return nmt_.send_command(command, node); }
  // Re-reads 1016h of the own dictionary (after it changed).
  void configure_heartbeat_consumers();

  bool on_frame(const can::Frame& frame, TimePoint now);
  void on_time(TimePoint now);
  TimePoint next_deadline() const;
  // Bus-state changes of the channel join the same sequence.
  void report(const can::BusEvent& ev);

  nmt::NmtMaster& nmt() { return nmt_; }
  sdo::SdoClient& sdo() { return sdo_; }
  pdo::PdoReceiver& pdo() { return pdo_; }
  // Process data to the nodes' RPDOs.
  pdo::PdoTransmitter& rpdo() { return rpdo_; }
  // The LSS master of this network (CiA 305, lss/master.hpp): it hears the
  // slaves' answers (7E4h) through on_frame(), its timeouts run in
  // on_time(), its submits report the deadline like the other services.
  lss::LssMaster& lss() { return lss_; }
  // The seq of the latest event (0: none yet, when the sequence started at 1).
  std::uint64_t last_seq() const { return seq_; }
  // The next event gets `next` (>= 1) and the sequence goes on from there:
  // a sequence kept across restarts (the gateway's state-dir) continues
  // instead of starting at 1 again. Call before the first event.
  void continue_sequence(std::uint64_t next) { seq_ = next == 0 ? 0 : next - 1; }

 private:
  void emit(EventBody body, can::Frame::Clock::time_point timestamp);
  void on_boot_event(const BootConfigEvent& ev);
  static bool found_without_boot_up(const NodeStateEvent& s);
  std::error_code check_transfer(std::uint8_t node) const;
  // The decoder or producer takes the PDO's configuration from pdo_table_.
  void refresh_pdo(std::uint8_t node, pdo::PdoKey key);

  const od::ObjectDictionary& own_;
  EventHandler on_event_;
  WallClock wall_;
  std::uint64_t seq_ = 0;
  // Receive time of the frame being dispatched; consumers that report
  // without a timestamp get this one.
  can::Frame::Clock::time_point frame_time_{};
  nmt::NmtMaster nmt_;
  sdo::SdoClient sdo_;
  pdo::PdoReceiver pdo_;
  pdo::PdoTransmitter rpdo_;
  lss::LssMaster lss_;
  std::unique_ptr<master::BootConfigurator> boot_;
  TimePoint now_{};  // the latest time given to on_frame()/on_time()
  emcy::EmcyConsumer emcy_;
  sync::SyncConsumer sync_;
  time::TimeConsumer time_;
  pdo::RemotePdoTable pdo_table_;
  pdo::PdoConfigReader pdo_reader_;
  master::DcfReader dcf_reader_;
  master::DcfApplier dcf_applier_;
  master::ProgramDownloader program_;
  // Nodes whose boot-up reads the PDO configuration -> NMT start afterwards.
  std::map<std::uint8_t, bool> boot_reads_;
  // Nodes found operational without a boot-up whose check runs: no NMT start after the PDO read.
  std::set<std::uint8_t> boot_checks_only_;
};

}  // namespace canopen
