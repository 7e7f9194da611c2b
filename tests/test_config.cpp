// The config file: errors name file, key and expectation.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <string>

#include "config/config_file.hpp"
#include "test_util.hpp"

namespace pipeloc {
namespace {

TEST(Config, ErrorsNameFileKeyAndExpectation) {
  test::TempDir dir;
  const auto error_of = [&](const std::string& text) {
    test::write_text(dir.file("c.toml"), text);
    try {
      load_config(dir.file("c.toml"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string msg = error_of("[locate]\nupward_normal_max_degrees = 20\n");
  EXPECT_NE(msg.find("c.toml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("locate.upward_normal_max_degrees: unknown key"), std::string::npos) << msg;
  msg = error_of("[locate]\nmax_candidates = 2.5\n");
  EXPECT_NE(msg.find("expected an integer"), std::string::npos) << msg;
  msg = error_of("[locate]\nverify_min_agreement = 3\n");
  EXPECT_NE(msg.find("in [0, 1]"), std::string::npos) << msg;
  msg = error_of("[locate]\nscan_step_deg = \"five\"\n");
  EXPECT_NE(msg.find("locate.scan_step_deg"), std::string::npos) << msg;
  msg = error_of("[locate\n");
  EXPECT_NE(msg.find("line 1"), std::string::npos) << msg;
  msg = error_of("[camera]\nfx = 1\n");
  EXPECT_NE(msg.find("unknown section"), std::string::npos) << msg;
  EXPECT_EQ(error_of("[model]\nstl = \"pipe.stl\"\n[locate]\nscan_step_deg = 2.5\nmax_candidates = 8\n"), "");
  const AppConfig cfg = load_config(dir.file("c.toml"));
  EXPECT_DOUBLE_EQ(cfg.locate.scan_step_deg, 2.5);
  EXPECT_EQ(cfg.locate.max_candidates, 8);
  EXPECT_EQ(cfg.model_path, dir.file("pipe.stl"));
}

// [status]: off by default; each key checked with a message naming it.
TEST(Config, StatusTableIsOffByDefaultAndChecksEveryKey) {
  test::TempDir dir;
  const AppConfig defaults = default_config();
  EXPECT_FALSE(defaults.status.enabled);
  EXPECT_EQ(defaults.status.address, "127.0.0.1");
  const auto error_of = [&](const std::string& text) {
    test::write_text(dir.file("c.toml"), text);
    try {
      load_config(dir.file("c.toml"));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  std::string msg = error_of("[status]\nenabled = 1\n");
  EXPECT_NE(msg.find("status.enabled: expected true or false"), std::string::npos) << msg;
  msg = error_of("[status]\naddress = \"localhost\"\n");
  EXPECT_NE(msg.find("status.address: expected an IPv4 address"), std::string::npos) << msg;
  msg = error_of("[status]\nport = 70000\n");
  EXPECT_NE(msg.find("status.port: expected an integer in [0, 65535]"), std::string::npos) << msg;
  msg = error_of("[status]\nrefresh_s = 0\n");
  EXPECT_NE(msg.find("status.refresh_s"), std::string::npos) << msg;
  msg = error_of("[status]\noverlay_every = -1\n");
  EXPECT_NE(msg.find("status.overlay_every"), std::string::npos) << msg;
  msg = error_of("[status]\nhost = \"0.0.0.0\"\n");
  EXPECT_NE(msg.find("status.host: unknown key"), std::string::npos) << msg;
  EXPECT_EQ(error_of("[status]\nenabled = true\naddress = \"0.0.0.0\"\nport = 0\noverlay_every = 5\n"
                     "refresh_s = 10\n"),
            "");
  const AppConfig cfg = load_config(dir.file("c.toml"));
  EXPECT_TRUE(cfg.status.enabled);
  EXPECT_EQ(cfg.status.address, "0.0.0.0");
  EXPECT_EQ(cfg.status.port, 0);
  EXPECT_EQ(cfg.status.overlay_every, 5);
  EXPECT_EQ(cfg.status.refresh_s, 10);
  bool listed = false;
  for (const std::string& line : cfg.effective)
    listed = listed || line == "status.port = 0  # TCP port (0: any free one)";
  EXPECT_TRUE(listed);
}

// config/demo.toml turns the status page on and lists every [status] key: it loads, and each key
// of the defaults appears in it.
TEST(Config, DemoConfigListsTheStatusKeys) {
  const AppConfig demo = load_config(std::string(PIPELOC_SOURCE_DIR) + "/config/demo.toml");
  EXPECT_TRUE(demo.status.enabled);
  EXPECT_EQ(demo.status.address, "127.0.0.1");
  std::ifstream in(std::string(PIPELOC_SOURCE_DIR) + "/config/demo.toml");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string section = text.substr(text.find("[status]"));
  int keys = 0;
  for (const std::string& line : default_config().effective) {
    if (line.rfind("status.", 0) != 0) continue;
    const std::string key = line.substr(7, line.find(' ') - 7);
    EXPECT_NE(section.find("\n" + key + " = "), std::string::npos) << key;
    ++keys;
  }
  EXPECT_EQ(keys, 5);
}

}  // namespace
}  // namespace pipeloc
