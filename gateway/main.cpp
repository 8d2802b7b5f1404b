// canopen-gateway: the command line (--help, --version, the flags of the
// contract); everything else, from reading the configuration to the orderly
// stop, is run_gateway() (gateway/app/process.hpp).
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "app/process.hpp"
#include "cli.hpp"

int main(int argc, char** argv) {
  gateway::CliOptions opts;
  try {
    opts = gateway::parse_cli(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const gateway::UsageError& e) {
    gateway::print_error(e.what());
    return gateway::kExitConfig;
  }
  if (opts.help) {
    std::fputs(gateway::help_text().c_str(), stdout);
    return 0;
  }
  if (opts.version) {
    std::puts("canopen-gateway " CANOPEN_GATEWAY_VERSION);
    return 0;
  }
  try {
    return gateway::run_gateway(opts);
  } catch (const std::exception& e) {
    gateway::print_error(e.what());
    return 1;
  }
}
