// Writes simulated frames as a BOP dataset (DESIGN.md data contract).
#pragma once

#include <string>

#include "sim/scene.hpp"

namespace pipeloc {

struct SimulateRequest {
  std::string out_dir;
  int images = 10;
  unsigned seed = 1;
  int scene_id = 1;
  int obj_id = 1;
  bool previews = true;  // preview_IIIIII.png: the depth shaded, for people to look at
  SceneParams scene;
};

// Writes models/, test/SSSSSS/ and test_targets_bop19.json. Throws IoError on I/O failure.
void write_simulated_dataset(const PipeModel& model, const SimulateRequest& request);

Json model_info_json(const PipeModel& model, const std::string& name);

}  // namespace pipeloc
