#include "locate/zbuffer.hpp"

#include <algorithm>

namespace pipeloc {

Pose bin_to_camera(const CameraInfo& camera) {
  if (camera.world_to_cam) return *camera.world_to_cam;
  Pose p = Pose::Identity();
  p.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();
  return p;
}

float seen_through_share(const ZBuffer& zb, const Eigen::Vector3f* pts, int n, float tol_mm) {
  if (n == 0) return 0;
  int through = 0;
  for (int k = 0; k < n; ++k) {
    const int i = int(round_nearest(float((pts[k].x() - zb.origin_x_mm) / zb.pixel_mm)));
    const int j = int(round_nearest(float((pts[k].y() - zb.origin_y_mm) / zb.pixel_mm)));
    through += zb.valid(i, j) && zb.z.at(i, j) < pts[k].z() - tol_mm;
  }
  return float(through) / float(n);
}

void reserve_zbuffer(ZBuffer* zb, double max_side_mm, double pixel_mm) {
  const int side = int(std::ceil(max_side_mm / pixel_mm)) + 1;
  zb->pixel_mm = pixel_mm;
  zb->z.resize(side, side, ZBuffer::kEmpty);
  zb->width = zb->height = 0;
}

int build_zbuffer(const Image<float>& depth, const Intrinsics& k, const Pose& bin_to_cam, ZBuffer* zb) {
  const Eigen::Matrix3f r = bin_to_cam.linear().transpose().cast<float>();  // camera -> bin
  const Eigen::Vector3f t = (-bin_to_cam.linear().transpose() * bin_to_cam.translation()).cast<float>();
  const auto to_bin = [&](int u, int v, float d) -> Eigen::Vector3f {
    return r * Eigen::Vector3f((u - float(k.cx)) * d / float(k.fx), (v - float(k.cy)) * d / float(k.fy), d) +
           t;
  };
  // Pass 1: extent of the valid points.
  float lo_x = 1e30f, lo_y = 1e30f, hi_x = -1e30f, hi_y = -1e30f;
  int valid = 0;
  for (int v = 0; v < depth.height; ++v)
    for (int u = 0; u < depth.width; ++u) {
      const float d = depth.at(u, v);
      if (!(d > 0)) continue;
      const Eigen::Vector3f p = to_bin(u, v, d);
      lo_x = std::min(lo_x, p.x()), hi_x = std::max(hi_x, p.x());
      lo_y = std::min(lo_y, p.y()), hi_y = std::max(hi_y, p.y());
      ++valid;
    }
  const double cap = (zb->z.width - 1) * zb->pixel_mm;
  if (valid == 0) {
    zb->width = zb->height = 0;
    return 0;
  }
  // Keep the middle of the scene when it is larger than the buffer.
  const double cx = 0.5 * (lo_x + hi_x), cy = 0.5 * (lo_y + hi_y);
  const double side_x = std::min<double>(hi_x - lo_x, cap), side_y = std::min<double>(hi_y - lo_y, cap);
  zb->origin_x_mm = cx - side_x / 2;
  zb->origin_y_mm = cy - side_y / 2;
  zb->width = int(side_x / zb->pixel_mm) + 1;
  zb->height = int(side_y / zb->pixel_mm) + 1;
  for (int j = 0; j < zb->height; ++j) std::fill_n(&zb->z.at(0, j), zb->width, ZBuffer::kEmpty);

  // Pass 2: splat each point over its footprint, keeping the highest.
  const float inv = float(1.0 / zb->pixel_mm);
  for (int v = 0; v < depth.height; ++v)
    for (int u = 0; u < depth.width; ++u) {
      const float d = depth.at(u, v);
      if (!(d > 0)) continue;
      const Eigen::Vector3f p = to_bin(u, v, d);
      const float half = 0.5f * d / float(k.fx) * inv;  // footprint half-width in cells
      const float ci = (p.x() - float(zb->origin_x_mm)) * inv, cj = (p.y() - float(zb->origin_y_mm)) * inv;
      const int i0 = std::max(0, int(round_nearest(ci - half))),
                i1 = std::min(zb->width - 1, int(round_nearest(ci + half)));
      const int j0 = std::max(0, int(round_nearest(cj - half))),
                j1 = std::min(zb->height - 1, int(round_nearest(cj + half)));
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          float& cell = zb->z.at(i, j);
          if (std::isnan(cell) || p.z() > cell) cell = p.z();
        }
    }
  return valid;
}

void fill_small_holes(ZBuffer* zb, int passes, float max_spread_mm, std::vector<float>* scratch) {
  // Specular glints and dropouts punch holes in a pipe's top; a hole is filled from its valid
  // neighbours only where they agree (no filling across the step between a pipe and the floor).
  for (int pass = 0; pass < passes; ++pass) {
    int filled = 0;
    for (int j = 1; j + 1 < zb->height; ++j)
      for (int i = 1; i + 1 < zb->width; ++i) {
        float& out = (*scratch)[std::size_t(zb->index(i, j))];
        out = zb->z.at(i, j);
        if (!std::isnan(out)) continue;
        float lo = 1e30f, hi = -1e30f, sum = 0;
        int n = 0;
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const float z = zb->z.at(i + di, j + dj);
            if (std::isnan(z)) continue;
            lo = std::min(lo, z), hi = std::max(hi, z), sum += z, ++n;
          }
        if (n >= 3 && hi - lo <= max_spread_mm) out = sum / float(n), ++filled;
      }
    if (filled == 0) break;
    for (int j = 1; j + 1 < zb->height; ++j)
      std::copy_n(&(*scratch)[std::size_t(zb->index(1, j))], zb->width - 2, &zb->z.at(1, j));
  }
}

}  // namespace pipeloc
