#include "canopen/pdo/remote_config.hpp"

#include "canopen/sdo/abort.hpp"

namespace canopen::pdo {

std::string_view to_string(ConfigSource s) {
  switch (s) {
    case ConfigSource::Eds: return "eds";
    case ConfigSource::Device: return "device";
    case ConfigSource::Written: return "written";
  }
  return "eds";
}

std::optional<PdoKey> pdo_of_index(std::uint16_t index) {
  if (index < 0x1400 || index > 0x1BFF) return std::nullopt;
  const Direction d = index >= 0x1800 ? Direction::Transmit : Direction::Receive;
  const auto number = static_cast<std::uint16_t>((index & 0x01FF) + 1);
  return PdoKey{d, number};
}

std::vector<std::string> RemotePdoTable::add_node(std::uint8_t node, od::ObjectDictionary description) {
  std::vector<std::string> problems;
  Node n;
  for (const Direction d : {Direction::Receive, Direction::Transmit}) {
    for (std::uint16_t number = 1; number <= kMaxPdoNumber; ++number) {
      if (description.find(comm_index(d, number)) == nullptr) continue;
      auto p = read_parameters(description, d, number);
      if (!p) {
        problems.push_back(p.error().detail);
        continue;
      }
      const PdoKey key{d, number};
      n.pdos[key] = RemotePdo{key, std::move(*p), ConfigSource::Eds, {}};
    }
  }
  n.description = std::move(description);
  nodes_[node] = std::move(n);
  return problems;
}

void RemotePdoTable::remove_node(std::uint8_t node) { nodes_.erase(node); }

std::optional<PdoKey> RemotePdoTable::apply_download(std::uint8_t node, std::uint16_t index, std::uint8_t sub,
                                                     std::span<const std::uint8_t> data) {
  auto key = pdo_of_index(index);
  auto n = nodes_.find(node);
  if (!key || n == nodes_.end() || data.empty() || data.size() > 4) return std::nullopt;
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < data.size(); ++i) v |= std::uint32_t{data[i]} << (8 * i);
  const bool mapping = (index & 0x0200) != 0;  // 1600h-17FFh, 1A00h-1BFFh
  if (mapping ? sub > kMaxMappedEntries : (sub == 0 || sub == 4 || sub > 6)) return std::nullopt;
  auto [it, fresh] = n->second.pdos.try_emplace(*key);
  RemotePdo& pdo = it->second;
  if (fresh) pdo.key = *key;  // unknown to the description: disabled, nothing mapped until written
  PdoParameters& p = pdo.parameters;
  if (mapping) {
    if (sub == 0) p.count = static_cast<std::uint8_t>(v);
    else p.entries[sub] = v;
  } else {
    switch (sub) {
      case 1: p.comm.cob_id.raw = v; break;
      case 2: p.comm.transmission_type = static_cast<std::uint8_t>(v); break;
      case 3: p.comm.inhibit_time = static_cast<std::uint16_t>(v); break;
      case 5: p.comm.event_timer = static_cast<std::uint16_t>(v); break;
      default: p.comm.sync_start = static_cast<std::uint8_t>(v); break;
    }
  }
  pdo.source = ConfigSource::Written;
  pdo.read_error.clear();
  return key;
}

bool RemotePdoTable::apply_read(std::uint8_t node, PdoKey key, const PdoParameters& parameters) {
  auto n = nodes_.find(node);
  if (n == nodes_.end()) return false;
  RemotePdo& pdo = n->second.pdos[key];
  pdo.key = key;
  // Entries beyond sub 0 were not read: the description's need not be the
  // device's, so they are forgotten rather than trusted after a later remap.
  pdo.parameters = parameters;
  pdo.source = ConfigSource::Device;
  pdo.read_error.clear();
  return true;
}

void RemotePdoTable::set_read_error(std::uint8_t node, PdoKey key, std::string reason) {
  auto n = nodes_.find(node);
  if (n == nodes_.end()) return;
  auto it = n->second.pdos.find(key);
  if (it != n->second.pdos.end()) it->second.read_error = std::move(reason);
}

const RemotePdo* RemotePdoTable::find(std::uint8_t node, PdoKey key) const {
  auto n = nodes_.find(node);
  if (n == nodes_.end()) return nullptr;
  auto it = n->second.pdos.find(key);
  return it == n->second.pdos.end() ? nullptr : &it->second;
}

std::vector<const RemotePdo*> RemotePdoTable::pdos(std::uint8_t node) const {
  std::vector<const RemotePdo*> out;
  auto n = nodes_.find(node);
  if (n == nodes_.end()) return out;
  for (const auto& [key, pdo] : n->second.pdos) out.push_back(&pdo);  // Receive < Transmit
  return out;
}

Result<PdoConfig> RemotePdoTable::resolve(std::uint8_t node, PdoKey key, std::size_t max_bytes) const {
  auto n = nodes_.find(node);
  const RemotePdo* pdo = find(node, key);
  if (pdo == nullptr)
    return Error{make_error_code(SdoAbort::NoSuchObject), "no such PDO on node " + std::to_string(node)};
  return resolve_pdo(key.direction, key.number, pdo->parameters, n->second.description, max_bytes);
}

const od::ObjectDictionary* RemotePdoTable::description(std::uint8_t node) const {
  auto n = nodes_.find(node);
  return n == nodes_.end() ? nullptr : &n->second.description;
}

}  // namespace canopen::pdo
