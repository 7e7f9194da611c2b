// The configuration the service tests share: the built-in defaults on the sim source, with the
// timing log in the test's own folder.
#pragma once

#include "config/config_file.hpp"
#include "test_util.hpp"

namespace pipeloc::test {

inline AppConfig sim_config(const TempDir& dir, int pipes, int seed) {
  AppConfig cfg = default_config();
  cfg.source.sim.pipes = pipes;
  cfg.source.sim.seed = seed;
  cfg.log.dir = dir.file("log");
  return cfg;
}

}  // namespace pipeloc::test
