// The config file: errors name file, key and expectation.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>

#include "config/config_file.hpp"
#include "test_util.hpp"

namespace pipeloc {
namespace {

// The message loading `text` as a config file gives (empty: it loaded).
std::string load_error(const test::TempDir& dir, const std::string& text) {
  test::write_text(dir.file("c.toml"), text);
  try {
    load_config(dir.file("c.toml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, ErrorsNameFileKeyAndExpectation) {
  test::TempDir dir;
  const auto error_of = [&](const std::string& text) { return load_error(dir, text); };
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
  // max_results 0 (the default): every pose found is reported, at most one per candidate.
  EXPECT_EQ(cfg.locate.max_results, 0);
  EXPECT_EQ(cfg.locate.result_cap(), 8);
  EXPECT_EQ(error_of("[locate]\nmax_results = 5\n"), "");
  EXPECT_EQ(load_config(dir.file("c.toml")).locate.result_cap(), 5);
  msg = error_of("[locate]\nmax_results = -1\n");
  EXPECT_NE(msg.find("locate.max_results"), std::string::npos) << msg;
}

// [status]: off by default; each key checked with a message naming it.
TEST(Config, StatusTableIsOffByDefaultAndChecksEveryKey) {
  test::TempDir dir;
  const AppConfig defaults = default_config();
  EXPECT_FALSE(defaults.status.enabled);
  EXPECT_EQ(defaults.status.address, "127.0.0.1");
  const auto error_of = [&](const std::string& text) { return load_error(dir, text); };
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

TEST(Config, UnknownSubTablesAreRejectedLikeUnknownKeys) {
  test::TempDir dir;
  for (const char* text :
       {"[locate.extra]\nfoo = 1\n", "[plc.server]\nport = 1\n", "[log.rotate]\n", "[model.grasp]\nx = 1\n",
        "[service.budget]\n", "[source.sim.noise]\nsigma = 1\n", "[source.camera]\n"}) {
    const std::string msg = load_error(dir, text);
    EXPECT_NE(msg.find("c.toml"), std::string::npos) << text << " -> " << msg;
    EXPECT_NE(msg.find("unknown section"), std::string::npos) << text << " -> " << msg;
  }
  EXPECT_NE(load_error(dir, "[locate.extra]\nfoo = 1\n").find("locate.extra"), std::string::npos);
  EXPECT_EQ(load_error(dir, "[source.sim]\npipes = 4\n[source.replay]\nmax_frames = 3\n"), "");
}

TEST(Config, KeysTheModeIgnoresAreWarnedAbout) {
  test::TempDir dir;
  const auto warnings_of = [&](const std::string& text) {
    test::write_text(dir.file("c.toml"), text);
    std::string all;
    for (const std::string& w : load_config(dir.file("c.toml")).warnings) all += w + "\n";
    return all;
  };
  std::string w = warnings_of("[plc]\nmode = \"server\"\npoll_ms = 20\nbyte_timeout_ms = 50\n");
  EXPECT_NE(w.find("plc.poll_ms is ignored"), std::string::npos) << w;
  EXPECT_NE(w.find("plc.byte_timeout_ms is ignored"), std::string::npos) << w;
  EXPECT_NE(w.find("c.toml"), std::string::npos) << w;
  w = warnings_of("[plc]\nmode = \"client\"\nmax_clients = 4\nplc_addresses = [\"10.0.0.1\"]\n");
  EXPECT_NE(w.find("plc.max_clients is ignored"), std::string::npos) << w;
  EXPECT_NE(w.find("plc.plc_addresses is ignored"), std::string::npos) << w;
  w = warnings_of("[source]\nkind = \"sim\"\n[source.openni2]\nuri = \"Dummy\"\n");
  EXPECT_NE(w.find("[source.openni2] is ignored"), std::string::npos) << w;
  // Keys the mode uses, and defaults, are no warning.
  EXPECT_EQ(warnings_of("[plc]\nmode = \"client\"\npoll_ms = 20\n[source.sim]\npipes = 3\n"), "");
}

// config/demo.toml claims to list every key of every section with its default: every key the
// loader accepts (default_config() records each one it reads) appears in its section, as a
// setting or, for another mode's or source's keys, commented out; and what it sets is the default.
TEST(Config, DemoTomlListsEveryKeyAtItsDefault) {
  std::ifstream in(PIPELOC_DEMO_TOML);
  ASSERT_TRUE(in) << PIPELOC_DEMO_TOML;
  std::set<std::string> listed;  // "section.key"
  const std::regex header(R"(^\s*#?\s*\[([a-z0-9_.]+)\]\s*(#.*)?$)");
  const std::regex key(R"(^\s*#?\s*([a-z0-9_]+)\s*=)");
  std::string section, line;
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_search(line, m, header))
      section = m[1];
    else if (!section.empty() && std::regex_search(line, m, key))
      listed.insert(section + "." + std::string(m[1]));
  }
  int keys = 0;
  for (const std::string& effective : default_config().effective) {
    const std::string name = effective.substr(0, effective.find(' '));
    ++keys;
    EXPECT_TRUE(listed.count(name)) << name << " is not in config/demo.toml";
  }
  EXPECT_GT(keys, 90);
  // Loaded, it is the embedded default, value for value, but for the status page it turns on
  // (Config.DemoConfigListsTheStatusKeys), and warns about nothing.
  const AppConfig demo = load_config(PIPELOC_DEMO_TOML);
  const auto without_status = [](std::vector<std::string> lines) {
    lines.erase(std::remove_if(lines.begin(), lines.end(),
                               [](const std::string& l) { return l.rfind("status.", 0) == 0; }),
                lines.end());
    return lines;
  };
  EXPECT_EQ(without_status(demo.effective), without_status(embedded_default_config().effective));
  EXPECT_TRUE(demo.warnings.empty()) << demo.warnings.front();
}

}  // namespace
}  // namespace pipeloc
