// A triangle mesh in mm, as read from STL or made by make_pipe.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace pipeloc {

struct Mesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<std::array<int, 3>> faces;

  Eigen::Vector3f face_normal(std::size_t f) const;  // unit, right-handed winding
  float face_area(std::size_t f) const;
  float surface_area() const;
};

// Merge vertices closer than tol_mm (STL stores each triangle's corners separately).
Mesh weld_vertices(const Mesh& soup, float tol_mm = 1e-4f);

// How the faces of a welded mesh wind, if it is closed: every edge shared by exactly two faces
// that run it in opposite directions. outward: right-handed normals point out of the enclosed
// volume; inward: into it; open: not closed that way (or encloses nothing).
enum class Winding { open, outward, inward };
Winding closed_winding(const Mesh& mesh);

struct ModelError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace pipeloc
