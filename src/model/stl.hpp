// STL in and out, binary and ASCII, units mm.
#pragma once

#include <string>

#include "model/mesh.hpp"

namespace pipeloc {

// Throws ModelError naming the file and what is wrong (missing, empty, truncated, not STL).
Mesh read_stl(const std::string& path);

enum class StlFormat { binary, ascii };
void write_stl(const std::string& path, const Mesh& mesh, StlFormat format = StlFormat::binary);

}  // namespace pipeloc
