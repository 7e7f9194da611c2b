#include "render/raster.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

double edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double x, double y) {
  return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
}

// Visits the integer pixel centres inside the screen triangle s0 s1 s2 (either winding).
template <typename Visit>
void scan_triangle(const Eigen::Vector2d& s0, const Eigen::Vector2d& s1, const Eigen::Vector2d& s2,
                   int width, int height, Visit visit) {
  const double area = edge(s0, s1, s2.x(), s2.y());
  if (std::abs(area) < 1e-12) return;
  const double sign = area > 0 ? 1.0 : -1.0;
  const int x0 = std::max(0, int(std::ceil(std::min({s0.x(), s1.x(), s2.x()}))));
  const int x1 = std::min(width - 1, int(std::floor(std::max({s0.x(), s1.x(), s2.x()}))));
  const int y0 = std::max(0, int(std::ceil(std::min({s0.y(), s1.y(), s2.y()}))));
  const int y1 = std::min(height - 1, int(std::floor(std::max({s0.y(), s1.y(), s2.y()}))));
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      if (sign * edge(s1, s2, x, y) >= 0 && sign * edge(s2, s0, x, y) >= 0 &&
          sign * edge(s0, s1, x, y) >= 0)
        visit(x, y);
}

}  // namespace

void DepthTarget::reset(int width, int height) {
  z_mm.resize(width, height, 0.0f);
  label.resize(width, height, -1);
  normal.resize(width, height, Eigen::Vector3f::Zero());
}

int render_perspective(const Mesh& mesh, const Pose& model_to_cam, const Intrinsics& k, int label,
                       DepthTarget* target) {
  const Eigen::Matrix3d r = model_to_cam.linear();
  const Eigen::Vector3d t = model_to_cam.translation();
  int won = 0;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d p0 = r * mesh.vertices[f[0]].cast<double>() + t;
    const Eigen::Vector3d p1 = r * mesh.vertices[f[1]].cast<double>() + t;
    const Eigen::Vector3d p2 = r * mesh.vertices[f[2]].cast<double>() + t;
    if (p0.z() <= 1 || p1.z() <= 1 || p2.z() <= 1) continue;  // behind or at the lens
    Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    if (n.norm() < 1e-12) continue;
    n.normalize();
    if (n.dot(p0) > 0) n = -n;  // face the camera: depth images see either side
    const double plane = n.dot(p0);
    scan_triangle(k.project(p0), k.project(p1), k.project(p2), target->z_mm.width,
                  target->z_mm.height, [&](int x, int y) {
                    // Exact depth where the pixel's ray meets the triangle's plane.
                    const Eigen::Vector3d ray((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1.0);
                    const double denom = n.dot(ray);
                    if (std::abs(denom) < 1e-9) return;
                    const float z = float(plane / denom);
                    float& cur = target->z_mm.at(x, y);
                    if (z > 0 && (cur == 0 || z < cur)) {
                      if (target->label.at(x, y) != label) ++won;
                      cur = z;
                      target->label.at(x, y) = label;
                      target->normal.at(x, y) = n.cast<float>();
                    }
                  });
  }
  return won;
}

float HeightMap::at(double x, double y, float outside) const {
  const Eigen::Vector2d c = to_cell(x, y);
  const int i = int(std::lround(c.x())), j = int(std::lround(c.y()));
  return z_mm.inside(i, j) ? z_mm.at(i, j) : outside;
}

void render_height(const Mesh& mesh, const Pose& model_to_world, Envelope which, HeightMap* map) {
  const Eigen::Matrix3d r = model_to_world.linear();
  const Eigen::Vector3d t = model_to_world.translation();
  const bool top = which == Envelope::top;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d p0 = r * mesh.vertices[f[0]].cast<double>() + t;
    const Eigen::Vector3d p1 = r * mesh.vertices[f[1]].cast<double>() + t;
    const Eigen::Vector3d p2 = r * mesh.vertices[f[2]].cast<double>() + t;
    const Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    if (std::abs(n.z()) < 1e-12) continue;  // vertical faces add nothing to a height map
    const double plane = n.dot(p0);
    scan_triangle(map->to_cell(p0.x(), p0.y()), map->to_cell(p1.x(), p1.y()),
                  map->to_cell(p2.x(), p2.y()), map->z_mm.width, map->z_mm.height,
                  [&](int i, int j) {
                    const double x = map->origin_x_mm + i * map->cell_mm;
                    const double y = map->origin_y_mm + j * map->cell_mm;
                    const float z = float((plane - n.x() * x - n.y() * y) / n.z());
                    float& cur = map->z_mm.at(i, j);
                    cur = top ? std::max(cur, z) : std::min(cur, z);
                  });
  }
}

}  // namespace pipeloc
