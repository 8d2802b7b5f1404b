// The PDO configuration of remote nodes as the gateway believes the devices
// hold it (CiA 301 7.2.2, records 1400h-1BFFh, 7.5.2.35-7.5.2.39): first
// the node's EDS/DCF, then whatever the gateway learns at run time - values
// its own SDO client wrote successfully (whoever asked: REST, MQTT, the
// boot-up DCF download) and values read back from the device. The PDO
// decoder (the node's TPDOs) and producer (its RPDOs) follow what is here;
// see Network.
//
// Mapped objects are always resolved against the node's description (its
// EDS/DCF dictionary): it is the only source of their types and names.
//
// Remapping (7.5.2.38 / 7.5.2.39: disable the PDO with COB-ID bit 31, set
// mapping sub 0 to 0, write the entries, set sub 0 to n, enable) passes
// through states that are stored as they are: a disabled PDO is not used,
// entries beyond sub 0 are kept for when sub 0 grows, and a mapping that
// does not resolve (an object the description does not have, a length that
// does not match its type, more than max_bytes) makes the PDO unusable
// with that reason rather than decoding it wrongly.
//
// Pure data; not thread-safe (one thread, like the Network that owns it).
#pragma once

#include <compare>
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "canopen/od/object_dictionary.hpp"
#include "canopen/pdo/mapping.hpp"
#include "canopen/result.hpp"

namespace canopen::pdo {

// Where the parameters in effect came from, latest first wins.
enum class ConfigSource : std::uint8_t {
  Eds,      // the node's EDS/DCF
  Device,   // read from the device by SDO
  Written,  // a successful SDO download by the gateway
};
std::string_view to_string(ConfigSource s);  // "eds", "device", "written"

struct PdoKey {
  Direction direction = Direction::Transmit;
  std::uint16_t number = 0;  // 1..512
  friend auto operator<=>(const PdoKey&, const PdoKey&) = default;
};

// The PDO whose communication or mapping record `index` is (1400h-1BFFh).
std::optional<PdoKey> pdo_of_index(std::uint16_t index);

struct RemotePdo {
  PdoKey key;
  PdoParameters parameters;
  ConfigSource source = ConfigSource::Eds;
  // Why the last read from the device did not replace these parameters
  // (empty: it did, or none was made).
  std::string read_error;
};

class RemotePdoTable {
 public:
  // Takes node's PDOs from its description: every PDO whose communication
  // and mapping records exist. Replaces what was known about the node.
  // Returns the PDOs that could not be taken ("TPDO3: reason").
  std::vector<std::string> add_node(std::uint8_t node, od::ObjectDictionary description);
  void remove_node(std::uint8_t node);
  bool has_node(std::uint8_t node) const { return nodes_.contains(node); }

  // A download of `data` (little-endian, 1..4 bytes) to node's index/sub
  // succeeded. Returns the PDO it changed: comm subs 1 (COB-ID), 2
  // (transmission type), 3 (inhibit time), 5 (event timer), 6 (SYNC start),
  // mapping subs 0-64. nullopt for anything else and for nodes not added.
  // A PDO the description lacks is created (disabled, empty mapping).
  std::optional<PdoKey> apply_download(std::uint8_t node, std::uint16_t index, std::uint8_t sub,
                                       std::span<const std::uint8_t> data);
  // Parameters read from the device replace the PDO's (source Device),
  // mapping entries beyond those read included. False for a node not added.
  bool apply_read(std::uint8_t node, PdoKey key, const PdoParameters& parameters);
  // A read of the PDO failed: the parameters stay, the reason is kept.
  void set_read_error(std::uint8_t node, PdoKey key, std::string reason);

  const RemotePdo* find(std::uint8_t node, PdoKey key) const;
  // The node's PDOs, RPDOs then TPDOs, in number order.
  std::vector<const RemotePdo*> pdos(std::uint8_t node) const;
  // The configuration in effect for one PDO, resolved against the node's
  // description; errors as resolve_pdo() (NoSuchObject: unknown PDO).
  Result<PdoConfig> resolve(std::uint8_t node, PdoKey key, std::size_t max_bytes = 8) const;
  // The node's description; nullptr for a node not added.
  const od::ObjectDictionary* description(std::uint8_t node) const;

 private:
  struct Node {
    od::ObjectDictionary description;
    std::map<PdoKey, RemotePdo> pdos;
  };
  std::map<std::uint8_t, Node> nodes_;
};

}  // namespace canopen::pdo
