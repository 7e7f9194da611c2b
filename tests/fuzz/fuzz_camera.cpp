// Fuzz target: scene_camera.json (BOP camera) and test targets readers.
#include <cstdint>
#include <exception>

#include "fuzz_file_util.hpp"
#include "io/bop.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz_input_file(data, size, ".json");
  try {
    pipeloc::read_scene_camera(path);
  } catch (const std::exception&) {
  }
  try {
    pipeloc::read_targets(path);
  } catch (const std::exception&) {
  }
  return 0;
}
