// Fuzz target: the TOML config loader with all its sections.
#include <cstdint>
#include <exception>

#include "config/config_file.hpp"
#include "fuzz_file_util.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = fuzz_input_file(data, size, ".toml");
  try {
    pipeloc::load_config(path);
  } catch (const std::exception&) {
  }
  return 0;
}
