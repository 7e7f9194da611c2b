#include "model/stl.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

namespace pipeloc {
namespace {

constexpr std::size_t kHeaderBytes = 80;
constexpr std::size_t kTriangleBytes = 50;  // normal, 3 vertices (12 float32), attribute u16

[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw ModelError("STL '" + path + "': " + what);
}

// A pipe in mm lies well within a kilometre; beyond, areas and volumes overflow float.
constexpr float kMaxCoordinateMm = 1e6f;
bool usable(float x, float y, float z) {
  return std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && std::abs(x) <= kMaxCoordinateMm &&
         std::abs(y) <= kMaxCoordinateMm && std::abs(z) <= kMaxCoordinateMm;
}

Mesh parse_binary(const std::string& path, const std::string& bytes) {
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + kHeaderBytes, 4);
  const std::size_t expected = kHeaderBytes + 4 + std::size_t(count) * kTriangleBytes;
  if (bytes.size() < expected)
    fail(path, "truncated: header announces " + std::to_string(count) + " triangles (" +
                   std::to_string(expected) + " bytes) but the file has " + std::to_string(bytes.size()) +
                   " bytes");
  if (count == 0) fail(path, "holds no triangles");
  Mesh soup;
  soup.vertices.reserve(std::size_t(count) * 3);
  soup.faces.reserve(count);
  for (std::uint32_t t = 0; t < count; ++t) {
    const char* p = bytes.data() + kHeaderBytes + 4 + std::size_t(t) * kTriangleBytes + 12;
    for (int k = 0; k < 3; ++k) {
      float xyz[3];
      std::memcpy(xyz, p + 12 * k, 12);
      if (!usable(xyz[0], xyz[1], xyz[2]))
        fail(path, "triangle " + std::to_string(t) + " has a coordinate that is not finite or beyond 1e6 mm");
      soup.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
    }
    const int b = int(t) * 3;
    soup.faces.push_back({b, b + 1, b + 2});
  }
  return soup;
}

Mesh parse_ascii(const std::string& path, const std::string& text) {
  std::istringstream in(text);
  std::string word;
  Mesh soup;
  int line_vertices = 0;
  while (in >> word) {
    if (word == "vertex") {
      float x, y, z;
      if (!(in >> x >> y >> z))
        fail(path, in.eof() ? "truncated: file ends inside a 'vertex' line"
                            : "malformed 'vertex' line (expected three numbers)");
      if (!usable(x, y, z))
        fail(path, "facet " + std::to_string(soup.faces.size()) +
                       ": vertex coordinate not finite or beyond 1e6 mm");
      soup.vertices.emplace_back(x, y, z);
      ++line_vertices;
    } else if (word == "endfacet") {
      if (line_vertices != 3)
        fail(path, "facet " + std::to_string(soup.faces.size()) + " has " + std::to_string(line_vertices) +
                       " vertices, expected 3");
      const int b = int(soup.vertices.size()) - 3;
      soup.faces.push_back({b, b + 1, b + 2});
      line_vertices = 0;
    }
  }
  if (line_vertices != 0) fail(path, "truncated: last facet has no 'endfacet'");
  if (soup.faces.empty()) fail(path, "ASCII STL holds no facets");
  if (text.find("endsolid") == std::string::npos) fail(path, "truncated: no 'endsolid'");
  return soup;
}

// Printable ASCII and whitespace only in the first bytes: a text file (a binary STL's header may
// be text, but its count and floats are not).
bool looks_like_text(const std::string& bytes) {
  const std::size_t n = std::min<std::size_t>(bytes.size(), 512);
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(bytes[i]);
    if (!(c == '\n' || c == '\r' || c == '\t' || (c >= 32 && c < 127))) return false;
  }
  return true;
}

// The first line (at most 40 characters) of a text file, for the message.
std::string first_line(const std::string& bytes) {
  std::string line = bytes.substr(0, std::min(bytes.find_first_of("\r\n"), std::size_t(40)));
  return line.size() == 40 ? line + "..." : line;
}

}  // namespace

Mesh read_stl(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a directory, not an STL file");
  std::ifstream file(path, std::ios::binary);
  if (!file) fail(path, "cannot open file");
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (bytes.empty()) fail(path, "file is empty");
  // A binary STL's size is fixed by its count; ASCII starts with "solid" and has facets.
  // Binary headers may also start with "solid", so the size test comes first.
  bool binary_size_matches = false;
  if (bytes.size() >= kHeaderBytes + 4) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + kHeaderBytes, 4);
    binary_size_matches = bytes.size() == kHeaderBytes + 4 + std::size_t(count) * kTriangleBytes;
  }
  const bool looks_ascii = bytes.compare(0, 5, "solid") == 0 && bytes.find("facet", 5) != std::string::npos;
  if (!binary_size_matches && bytes.compare(0, 5, "solid") != 0 && looks_like_text(bytes))
    fail(path, "not an STL file: it is text (first line \"" + first_line(bytes) +
                   "\"), neither a binary STL nor an ASCII one ('solid' with 'facet' lines)");
  Mesh soup;
  if (binary_size_matches ||
      (!looks_ascii && bytes.size() >= kHeaderBytes + 4 && bytes.compare(0, 5, "solid") != 0)) {
    soup = parse_binary(path, bytes);
  } else if (looks_ascii) {
    soup = parse_ascii(path, bytes);
  } else if (bytes.compare(0, 5, "solid") == 0) {
    fail(path, "starts with 'solid' but has no facets (empty or truncated ASCII STL)");
  } else {
    fail(path, "not an STL file (" + std::to_string(bytes.size()) +
                   " bytes: too short for a binary header and not ASCII 'solid')");
  }
  Mesh mesh = weld_vertices(soup);
  if (mesh.faces.empty()) fail(path, "all triangles are degenerate");
  return mesh;
}

void write_stl(const std::string& path, const Mesh& mesh, StlFormat format) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw ModelError("STL '" + path + "': cannot open for writing");
  if (format == StlFormat::ascii) {
    out << "solid pipeloc\n";
    out.precision(9);
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
      const Eigen::Vector3f n = mesh.face_normal(f);
      out << " facet normal " << n.x() << ' ' << n.y() << ' ' << n.z() << "\n  outer loop\n";
      for (int k = 0; k < 3; ++k) {
        const auto& v = mesh.vertices[mesh.faces[f][k]];
        out << "   vertex " << v.x() << ' ' << v.y() << ' ' << v.z() << '\n';
      }
      out << "  endloop\n endfacet\n";
    }
    out << "endsolid pipeloc\n";
  } else {
    char header[kHeaderBytes] = "pipeloc binary STL, mm";
    out.write(header, kHeaderBytes);
    const std::uint32_t count = std::uint32_t(mesh.faces.size());
    out.write(reinterpret_cast<const char*>(&count), 4);
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
      const Eigen::Vector3f n = mesh.face_normal(f);
      out.write(reinterpret_cast<const char*>(n.data()), 12);
      for (int k = 0; k < 3; ++k)
        out.write(reinterpret_cast<const char*>(mesh.vertices[mesh.faces[f][k]].data()), 12);
      const std::uint16_t attribute = 0;
      out.write(reinterpret_cast<const char*>(&attribute), 2);
    }
  }
  if (!out) throw ModelError("STL '" + path + "': write failed");
}

}  // namespace pipeloc
