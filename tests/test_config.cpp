// The config file: errors name file, key and expectation.
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace pipeloc
