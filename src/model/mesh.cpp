#include "model/mesh.hpp"

#include <cmath>
#include <map>
#include <tuple>

namespace pipeloc {

Eigen::Vector3f Mesh::face_normal(std::size_t f) const {
  const auto& t = faces[f];
  const Eigen::Vector3f n = (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]);
  const float len = n.norm();
  return len > 0 ? Eigen::Vector3f(n / len) : Eigen::Vector3f::Zero();
}

float Mesh::face_area(std::size_t f) const {
  const auto& t = faces[f];
  return 0.5f * (vertices[t[1]] - vertices[t[0]]).cross(vertices[t[2]] - vertices[t[0]]).norm();
}

float Mesh::surface_area() const {
  float sum = 0;
  for (std::size_t f = 0; f < faces.size(); ++f) sum += face_area(f);
  return sum;
}

Winding closed_winding(const Mesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) ++directed[{f[std::size_t(k)], f[std::size_t((k + 1) % 3)]}];
  for (const auto& [edge, count] : directed) {
    if (count != 1) return Winding::open;
    const auto reverse = directed.find({edge.second, edge.first});
    if (reverse == directed.end() || reverse->second != 1) return Winding::open;
  }
  // Signed volume: sum of the tetrahedra from the origin to each face.
  double volume = 0;
  for (const auto& f : mesh.faces)
    volume += mesh.vertices[f[0]].cast<double>().dot(
        mesh.vertices[f[1]].cast<double>().cross(mesh.vertices[f[2]].cast<double>()));
  if (volume == 0) return Winding::open;
  return volume > 0 ? Winding::outward : Winding::inward;
}

Mesh weld_vertices(const Mesh& soup, float tol_mm) {
  using Key = std::tuple<long, long, long>;
  std::map<Key, int> index;
  Mesh out;
  std::vector<int> remap(soup.vertices.size());
  for (std::size_t i = 0; i < soup.vertices.size(); ++i) {
    const auto& v = soup.vertices[i];
    const Key key{std::lround(v.x() / tol_mm), std::lround(v.y() / tol_mm), std::lround(v.z() / tol_mm)};
    auto [it, inserted] = index.emplace(key, int(out.vertices.size()));
    if (inserted) out.vertices.push_back(v);
    remap[i] = it->second;
  }
  for (const auto& f : soup.faces) {
    const std::array<int, 3> g{remap[f[0]], remap[f[1]], remap[f[2]]};
    if (g[0] != g[1] && g[1] != g[2] && g[0] != g[2]) out.faces.push_back(g);
  }
  return out;
}

}  // namespace pipeloc
