// The TOML configuration, validated once at start-up: an unknown key, a wrong type or a value
// out of range stops the program with a message naming the file, the key and what was expected.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "locate/locate_config.hpp"

namespace pipeloc {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct AppConfig {
  std::string model_path;  // [model] stl = "...", relative to the config file
  LocateConfig locate;
};

AppConfig load_config(const std::string& path);
// Every value in effect, one "section.key = value" line each, for the start-up log.
std::vector<std::string> describe_config(const AppConfig& cfg);

}  // namespace pipeloc
