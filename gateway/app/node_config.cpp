#include <algorithm>
#include <filesystem>

#include <boost/json/serialize.hpp>

#include "app/network_unit.hpp"
#include "app/node_configs.hpp"
#include "app/node_overlay.hpp"
#include "pipeline/stack_output.hpp"
#include "state_file.hpp"

namespace gateway {

namespace fs = std::filesystem;

namespace {

core::Problem problem(int status, std::string detail) {
  core::Problem p;
  p.status = status;
  p.detail = std::move(detail);
  return p;
}

const NodeConfig* find_node(const std::vector<NodeConfig>& nodes, std::uint8_t id) {
  auto it = std::find_if(nodes.begin(), nodes.end(), [id](const NodeConfig& n) { return n.id == id; });
  return it == nodes.end() ? nullptr : &*it;
}

}  // namespace

core::NodeConfigView App::NodeConfigs::node_config(std::uint32_t net, std::uint8_t node) const {
  const NetworkUnit& unit = *app.nets_[net - 1];
  core::NodeConfigView v;
  v.network = net;
  v.node = node;
  const NodeConfig* n = find_node(unit.cfg.nodes, node);
  if (n == nullptr) {
    v.source = "none";
    return v;
  }
  v.settings = *n;
  if (auto it = unit.overlay_files.find(node); it != unit.overlay_files.end()) {
    v.source = "state-dir";
    v.file = it->second;
  } else {
    v.source = "config";
  }
  return v;
}

core::Result App::NodeConfigs::write_node_config(std::uint32_t net, std::uint8_t, const NodeConfig& settings) {
  NetworkUnit& unit = *app.nets_[net - 1];
  std::optional<canopen::eds::DeviceDescription> desc;
  if (!settings.eds.empty()) {
    try {
      desc = unit.load_description(settings);
    } catch (const canopen::eds::EdsError& e) {
      return problem(400, e.what());
    }
  }
  return change(net, settings, std::move(desc));
}

core::Result App::NodeConfigs::write_node_eds(std::uint32_t net, std::uint8_t node,
                                              canopen::eds::DeviceDescription description, std::string_view text) {
  const NetworkUnit& unit = *app.nets_[net - 1];
  NodeConfig n;
  n.id = node;
  if (const NodeConfig* now = find_node(unit.cfg.nodes, node)) n = *now;  // the other settings stay
  const auto file = node_eds_file(app.config_.state_dir, net, node, description.is_dcf).string();
  n.eds = file;
  return change(net, std::move(n), std::move(description), text, file);
}

core::Result App::NodeConfigs::change(std::uint32_t net, NodeConfig node,
                                      std::optional<canopen::eds::DeviceDescription> description,
                                      std::string_view eds_text, const std::string& eds_file) {
  NetworkUnit& unit = *app.nets_[net - 1];
  const std::string& state_dir = app.config_.state_dir;
  if (state_dir.empty())
    return problem(409, "no state-dir is configured (gateway.state-dir): a change would be lost at the next start");
  if (auto why = unit.cannot_apply(node); !why.empty()) return problem(409, why);
  // Kept first: what is applied is what a restart will find.
  const auto settings_file = node_settings_file(state_dir, net, node.id);
  std::error_code ec;
  fs::create_directories(settings_file.parent_path(), ec);
  if (!ec && !eds_file.empty()) ec = write_durably(eds_file, eds_text);
  if (!ec) ec = write_durably(settings_file, boost::json::serialize(node_config_json(node)) + "\n");
  if (ec)
    return problem(500, "cannot keep the settings in " + settings_file.parent_path().string() + ": " + ec.message() +
                            "; nothing changed");
  if (!eds_file.empty()) {
    // An earlier upload of the other kind (EDS vs DCF) is no longer the node's.
    const bool dcf = eds_file.ends_with(".dcf");
    fs::remove(node_eds_file(state_dir, net, node.id, !dcf), ec);
  }
  unit.overlay_files[node.id] = settings_file.string();
  apply(net, node, std::move(description));
  return node_config(net, node.id);
}

void App::NodeConfigs::apply(std::uint32_t net, const NodeConfig& node,
                             std::optional<canopen::eds::DeviceDescription> description) {
  NetworkUnit& unit = *app.nets_[net - 1];
  const bool described = description.has_value();
  unit.apply_node(node, std::move(description));
  app.history_.forget_node(net, node.id);  // another device or mapping: its old values are not this one's
  app.cache_.add_configured_node(net, node.id, node.name);
  for (auto& o : app.outputs_) o->node_changed(net, node);  // Sparkplug: a new DBIRTH
  app.log_.info(unit.label + " node " + std::to_string(node.id) + ": settings applied at run time (" +
                (described ? "EDS/DCF " + node.eds : std::string("no EDS/DCF")) + ")");
}

core::Result App::NodeConfigs::revert_node_config(std::uint32_t net, std::uint8_t node) {
  NetworkUnit& unit = *app.nets_[net - 1];
  if (!unit.overlay_files.contains(node)) return node_config(net, node);  // nothing kept: already the file's
  const NodeConfig* file = find_node(unit.file_nodes, node);
  std::optional<canopen::eds::DeviceDescription> desc;
  if (file != nullptr && !file->eds.empty()) {
    try {
      desc = unit.load_description(*file);
    } catch (const canopen::eds::EdsError& e) {
      return problem(409, "the configuration file's EDS/DCF for node " + std::to_string(node) +
                              " cannot be read now: " + e.what() + "; nothing changed");
    }
  }
  const std::string& state_dir = app.config_.state_dir;
  std::error_code ec;
  fs::remove(node_settings_file(state_dir, net, node), ec);
  if (ec) return problem(500, "cannot remove " + unit.overlay_files[node] + ": " + ec.message() + "; nothing changed");
  for (const bool dcf : {false, true}) fs::remove(node_eds_file(state_dir, net, node, dcf), ec);
  unit.overlay_files.erase(node);
  if (file != nullptr) {
    apply(net, *file, std::move(desc));
  } else {
    unit.remove_node(node);
    app.history_.forget_node(net, node);
    app.cache_.unconfigure_node(net, node);
    NodeConfig gone;  // no longer configured: its id only, nothing listed
    gone.id = node;
    for (auto& o : app.outputs_) o->node_changed(net, gone);
    app.log_.info(unit.label + " node " + std::to_string(node) + ": run-time settings dropped; not configured");
  }
  return node_config(net, node);
}

}  // namespace gateway
