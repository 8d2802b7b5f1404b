#include "pipeline/pipeline.hpp"

namespace gateway {

EventPipeline::EventPipeline(Encoder encoder, StateCache& cache, std::size_t history_capacity)
    : encoder_(std::move(encoder)), cache_(cache), ring_(history_capacity == 0 ? 1 : history_capacity) {}

void EventPipeline::on_event(std::uint32_t network, const canopen::Event& ev) {
  cache_.apply(network, ev);  // before consumers: a REST call they trigger sees the new state
  if (auto encoded = encoder_(network, ev)) fan_out(encoded);
}

void EventPipeline::publish(const EncodedEventPtr& ev) {
  if (ev) fan_out(ev);
}

void EventPipeline::fan_out(const EncodedEventPtr& ev) {
  ring_[ring_next_] = ev;
  ring_next_ = (ring_next_ + 1) % ring_.size();
  ++total_;
  ++published_[static_cast<std::size_t>(ev->kind)];
  for (const auto& c : consumers_) c(ev);
}

std::vector<EncodedEventPtr> EventPipeline::recent(std::size_t max, std::optional<std::uint32_t> network) const {
  std::vector<EncodedEventPtr> out;
  // Walk backwards from the newest, then reverse: oldest first.
  for (std::size_t i = 0; i < ring_.size() && out.size() < max; ++i) {
    const auto& ev = ring_[(ring_next_ + ring_.size() - 1 - i) % ring_.size()];
    if (!ev) break;
    if (network && ev->network != *network) continue;
    out.push_back(ev);
  }
  return {out.rbegin(), out.rend()};
}

}  // namespace gateway
