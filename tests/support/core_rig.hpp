// A RequestCore on a FakeNetworks with its audit lines collected, and
// helpers to build requests and read answers (tests/unit/gateway/core).
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/request_core.hpp"
#include "support/fake_networks.hpp"

namespace gateway::core::test_support {

struct Rig {
  explicit Rig(RequestCore::Settings s = {}, std::vector<auth::TokenEntry> t = {})
      : tokens(std::move(t)), core(nets, tokens, s, [this](const std::string& l) { audit.push_back(l); }) {}

  // Executes and returns where the result will be.
  std::shared_ptr<std::optional<Result>> run(Request r) {
    auto out = std::make_shared<std::optional<Result>>();
    core.execute(std::move(r), [out](Result res) {
      EXPECT_FALSE(out->has_value()) << "answered twice";
      *out = std::move(res);
    });
    return out;
  }
  bool audited(std::string_view part) const {
    for (const auto& l : audit)
      if (l.find(part) != std::string::npos) return true;
    return false;
  }

  FakeNetworks nets;
  auth::TokenStore tokens;
  std::vector<std::string> audit;
  RequestCore core;
};

inline Caller checked(Role role, std::string key = "address 10.0.0.7", std::string who = "op@10.0.0.7") {
  Caller c;
  c.authenticated = true;
  c.role = role;
  c.key = std::move(key);
  c.who = std::move(who);
  return c;
}

inline Request request(Command cmd, Caller caller = checked(Role::Admin), std::uint32_t net = 1) {
  Request r;
  r.caller = std::move(caller);
  r.network = net;
  r.command = std::move(cmd);
  return r;
}

inline const Problem& problem_of(const std::shared_ptr<std::optional<Result>>& r) {
  static const Problem none{0, "no problem", {}, {}, {}, 0, true, {}};
  if (!r->has_value() || !std::holds_alternative<Problem>(**r)) {
    ADD_FAILURE() << "not a problem";
    return none;
  }
  return std::get<Problem>(**r);
}

}  // namespace gateway::core::test_support
