// Fuzz target: the 16-bit depth PNG reader.
#include <cstdint>
#include <exception>

#include "fuzz_file_util.hpp"
#include "io/bop.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz_input_file(data, size, ".png");
  try {
    pipeloc::read_depth_mm(path, 1.0);
  } catch (const std::exception&) {
  }
  return 0;
}
