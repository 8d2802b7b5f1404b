// check_state_dirs() (gateway/config/state_dirs.cpp): a state directory the
// gateway cannot write is a configuration error at start-up, naming the key,
// where it came from and why (issue 12 item 6).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "config/config.hpp"

namespace gateway {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class StateDirs : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string tmpl = (fs::temp_directory_path() / "state-dirs-XXXXXX").string();
    root_ = ::mkdtemp(tmpl.data());
    // A regular file: no directory can be made below it (ENOTDIR), as root too.
    std::ofstream(root_ / "file") << "x";
  }
  void TearDown() override { fs::remove_all(root_); }

  // The configuration as canopen-gateway builds it.
  Config merged(const std::string& yaml) {
    const auto file = (root_ / "gw.yaml").string();
    std::ofstream(file) << yaml;
    CliOptions cli;
    cli.demo = true;
    return merge(load_config(file), cli);
  }
  static std::string error(const Config& c) {
    try {
      check_state_dirs(c);
    } catch (const ConfigError& e) {
      return e.what();
    }
    ADD_FAILURE() << "expected a ConfigError";
    return {};
  }

  fs::path root_;
};

TEST_F(StateDirs, AMissingDirectoryIsCreated) {
  const Config c = merged("gateway: {state-dir: state/a}\nmqtt: {uri: tcp://b:1}\n");
  EXPECT_NO_THROW(check_state_dirs(c));
  EXPECT_TRUE(fs::is_directory(root_ / "state/a"));
  EXPECT_TRUE(fs::is_directory(root_ / "state/a/mqtt-queue"));
  EXPECT_TRUE(fs::is_empty(root_ / "state/a/mqtt-queue")) << "the probe file is gone";
}

TEST_F(StateDirs, AnUnusableStateDirNamesFileKeyDirectoryAndReason) {
  const Config c = merged("gateway:\n  state-dir: file/state\n");
  const auto e = error(c);
  EXPECT_THAT(e, HasSubstr(root_.string() + "/gw.yaml:2: gateway.state-dir: '" + root_.string() + "/file/state'"));
  EXPECT_THAT(e, HasSubstr("Not a directory"));
  EXPECT_EQ(e.find('\n'), std::string::npos) << "one line";
}

TEST_F(StateDirs, AnUnusableQueueDirIsCheckedWithMqttOnOnly) {
  const std::string yaml = "gateway: {state-dir: ok}\nmqtt:\n  uri: tcp://b:1\n  queue: {dir: file/q}\n";
  const auto e = error(merged(yaml));
  EXPECT_THAT(e, HasSubstr("gw.yaml:4: mqtt.queue.dir: '" + root_.string() + "/file/q'"));
  Config off = merged(yaml);
  off.mqtt.enabled = false;
  EXPECT_NO_THROW(check_state_dirs(off));
}

// Not from the file: the message says which default or variable it was.
TEST_F(StateDirs, ADefaultFromTheEnvironmentIsNamedAsSuch) {
  ::setenv("STATE_DIRECTORY", (root_ / "file/x").c_str(), 1);
  const Config c = merged("");
  ::unsetenv("STATE_DIRECTORY");
  EXPECT_THAT(error(c), HasSubstr("gateway.state-dir from $STATE_DIRECTORY (systemd StateDirectory=): '" +
                                  root_.string() + "/file/x'"));
}

// Access bits are no answer as root: the check writes. Only where it can
// be seen (not as root, which may write anywhere).
TEST_F(StateDirs, AReadOnlyDirectoryIsRefused) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into a mode 0555 directory; ENOTDIR above covers the check";
  fs::create_directory(root_ / "ro");
  fs::permissions(root_ / "ro", fs::perms::owner_read | fs::perms::owner_exec);
  const auto e = error(merged("gateway: {state-dir: ro}\n"));
  fs::permissions(root_ / "ro", fs::perms::owner_all);
  EXPECT_THAT(e, HasSubstr("Permission denied"));
}

}  // namespace
}  // namespace gateway
