// Fuzz target: the STL loader (binary and ASCII) and, for small meshes, the model derivation.
#include <cstdint>
#include <exception>

#include "fuzz_file_util.hpp"
#include "model/pipe_model.hpp"
#include "model/stl.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz_input_file(data, size, ".stl");
  try {
    pipeloc::Mesh mesh = pipeloc::read_stl(path);
    if (mesh.faces.size() <= 64) {
      pipeloc::ModelDerivation d;
      d.max_samples = 2000;
      pipeloc::derive_pipe_model(std::move(mesh), path, d);
    }
  } catch (const std::exception&) {  // a clear error is the right answer to a bad file
  }
  return 0;
}
