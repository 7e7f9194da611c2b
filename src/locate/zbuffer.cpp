#include "locate/zbuffer.hpp"

#include <algorithm>
#include <limits>

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

void reserve_zbuffer_points(ZBufferPoints* pts, int width, int height, int bands) {
  pts->width = width, pts->height = height;
  pts->p.assign(std::size_t(width) * height, Eigen::Vector4f::Zero());
  pts->band.assign(std::size_t(std::max(1, bands)), {});
  pts->row.assign(std::size_t(height), {});
}

void zbuffer_points_rows(const Image<float>& depth, const Intrinsics& k, const Pose& bin_to_cam,
                         double pixel_mm, int v0, int v1, int band, ZBufferPoints* pts,
                         const RegionOfInterest& roi) {
  const bool clip = roi.on();
  const float roi_lo_x = float(roi.min_x_mm), roi_lo_y = float(roi.min_y_mm), roi_hi_x = float(roi.max_x_mm),
              roi_hi_y = float(roi.max_y_mm);
  const Eigen::Matrix3f r = bin_to_cam.linear().transpose().cast<float>();  // camera -> bin
  const Eigen::Vector3f t = (-bin_to_cam.linear().transpose() * bin_to_cam.translation()).cast<float>();
  const float fx = float(k.fx), fy = float(k.fy), cx = float(k.cx), cy = float(k.cy);
  const float inv = float(1.0 / pixel_mm);
  ZBufferPoints::Extent e;
  for (int v = v0; v < v1; ++v) {
    ZBufferPoints::RowSpan span{1e30f, -1e30f, -1};
    for (int u = 0; u < depth.width; ++u) {
      Eigen::Vector4f& out = pts->p[std::size_t(v) * depth.width + u];
      const float d = depth.at(u, v);
      if (!(d > 0)) {
        out.w() = -1;
        continue;
      }
      const Eigen::Vector3f p =
          r * Eigen::Vector3f((float(u) - cx) * d / fx, (float(v) - cy) * d / fy, d) + t;
      if (clip && !(p.x() >= roi_lo_x && p.x() <= roi_hi_x && p.y() >= roi_lo_y && p.y() <= roi_hi_y)) {
        out.w() = -1;
        continue;
      }
      out = Eigen::Vector4f(p.x(), p.y(), p.z(), 0.5f * d / fx * inv);
      e.lo_x = std::min(e.lo_x, p.x()), e.hi_x = std::max(e.hi_x, p.x());
      e.lo_y = std::min(e.lo_y, p.y()), e.hi_y = std::max(e.hi_y, p.y());
      ++e.valid;
      span.lo_y = std::min(span.lo_y, p.y()), span.hi_y = std::max(span.hi_y, p.y());
      span.half = std::max(span.half, out.w());
    }
    pts->row[std::size_t(v)] = span;
  }
  pts->band[std::size_t(band)] = e;
}

int place_zbuffer(const ZBufferPoints& pts, int bands, ZBuffer* zb) {
  ZBufferPoints::Extent all;
  for (int b = 0; b < bands; ++b) {
    const ZBufferPoints::Extent& e = pts.band[std::size_t(b)];
    all.lo_x = std::min(all.lo_x, e.lo_x), all.hi_x = std::max(all.hi_x, e.hi_x);
    all.lo_y = std::min(all.lo_y, e.lo_y), all.hi_y = std::max(all.hi_y, e.hi_y);
    all.valid += e.valid;
  }
  if (all.valid == 0) {
    zb->width = zb->height = 0;
    return 0;
  }
  // Keep the middle of the scene when it is larger than the buffer.
  const double cap = (zb->z.width - 1) * zb->pixel_mm;
  const double cx = 0.5 * (all.lo_x + all.hi_x), cy = 0.5 * (all.lo_y + all.hi_y);
  const double side_x = std::min<double>(all.hi_x - all.lo_x, cap),
               side_y = std::min<double>(all.hi_y - all.lo_y, cap);
  zb->origin_x_mm = cx - side_x / 2;
  zb->origin_y_mm = cy - side_y / 2;
  zb->width = int(side_x / zb->pixel_mm) + 1;
  zb->height = int(side_y / zb->pixel_mm) + 1;
  return all.valid;
}

void splat_zbuffer_rows(const ZBufferPoints& pts, int j0, int j1, ZBuffer* zb) {
  j1 = std::min(j1, zb->height);
  // Empty cells are -inf while splatting (a plain max), NaN again after.
  constexpr float kLowest = -std::numeric_limits<float>::infinity();
  for (int j = j0; j < j1; ++j) std::fill_n(&zb->z.at(0, j), zb->width, kLowest);
  const float inv = float(1.0 / zb->pixel_mm);
  const float ox = float(zb->origin_x_mm), oy = float(zb->origin_y_mm);
  for (int v = 0; v < pts.height; ++v) {
    // The rows a point reaches grow with its y and its footprint: an image row whose extremes
    // cannot reach these rows holds no point that can.
    const ZBufferPoints::RowSpan& span = pts.row[std::size_t(v)];
    if (span.half < 0 || int(round_nearest((span.hi_y - oy) * inv + span.half)) < j0 ||
        int(round_nearest((span.lo_y - oy) * inv - span.half)) > j1 - 1)
      continue;
    const Eigen::Vector4f* image_row = &pts.p[std::size_t(v) * pts.width];
    for (int u = 0; u < pts.width; ++u) {
      const Eigen::Vector4f& p = image_row[u];
      const float half = p.w();
      if (half < 0) continue;
      const float cj = (p.y() - oy) * inv;
      const int jlo = std::max(j0, int(round_nearest(cj - half))),
                jhi = std::min(j1 - 1, int(round_nearest(cj + half)));
      if (jlo > jhi) continue;
      const float ci = (p.x() - ox) * inv;
      const int i0 = std::max(0, int(round_nearest(ci - half))),
                i1 = std::min(zb->width - 1, int(round_nearest(ci + half)));
      for (int j = jlo; j <= jhi; ++j) {
        float* row = &zb->z.at(0, j);
        for (int i = i0; i <= i1; ++i) row[i] = std::max(row[i], p.z());
      }
    }
  }
  for (int j = j0; j < j1; ++j) {
    float* row = &zb->z.at(0, j);
    for (int i = 0; i < zb->width; ++i)
      if (row[i] == kLowest) row[i] = ZBuffer::kEmpty;
  }
}

int build_zbuffer(const Image<float>& depth, const Intrinsics& k, const Pose& bin_to_cam, ZBufferPoints* pts,
                  ZBuffer* zb) {
  zbuffer_points_rows(depth, k, bin_to_cam, zb->pixel_mm, 0, depth.height, 0, pts);
  const int valid = place_zbuffer(*pts, 1, zb);
  splat_zbuffer_rows(*pts, 0, zb->height, zb);
  return valid;
}

int collect_holes_rows(const ZBuffer& zb, int j0, int j1, HoleList* holes) {
  int n = 0;
  int* out = &holes->cell[std::size_t(zb.index(0, j0))];  // a band's holes lie in its own rows' slots
  for (int j = std::max(1, j0); j < std::min(j1, zb.height - 1); ++j)
    for (int i = 1; i + 1 < zb.width; ++i)
      if (std::isnan(zb.z.at(i, j))) out[n++] = zb.index(i, j);
  return n;
}

int fill_holes_pass(const ZBuffer& zb, float max_spread_mm, int j0, int count, HoleList* holes) {
  // Specular glints and dropouts punch holes in a pipe's top; a hole is filled from its valid
  // neighbours only where they agree (no filling across the step between a pipe and the floor).
  const int* cells = &holes->cell[std::size_t(zb.index(0, j0))];
  float* value = &holes->value[std::size_t(zb.index(0, j0))];
  const int w = zb.z.width;
  int filled = 0;
  for (int k = 0; k < count; ++k) {
    const float* centre = &zb.z.pixels[std::size_t(cells[k])];
    float lo = 1e30f, hi = -1e30f, sum = 0;
    int n = 0;
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const float z = centre[dj * w + di];
        if (std::isnan(z)) continue;
        lo = std::min(lo, z), hi = std::max(hi, z), sum += z, ++n;
      }
    const bool fill = n >= 3 && hi - lo <= max_spread_mm;
    value[k] = fill ? sum / float(n) : ZBuffer::kEmpty;
    filled += fill;
  }
  return filled;
}

int apply_filled(int j0, int count, HoleList* holes, ZBuffer* zb) {
  int* cells = &holes->cell[std::size_t(zb->index(0, j0))];
  const float* value = &holes->value[std::size_t(zb->index(0, j0))];
  int left = 0;
  for (int k = 0; k < count; ++k) {
    if (std::isnan(value[k]))
      cells[left++] = cells[k];
    else
      zb->z.pixels[std::size_t(cells[k])] = value[k];
  }
  return left;
}

void fill_small_holes(ZBuffer* zb, int passes, float max_spread_mm, HoleList* holes) {
  int count = collect_holes_rows(*zb, 0, zb->height, holes);
  for (int pass = 0; pass < passes && count > 0; ++pass) {
    if (fill_holes_pass(*zb, max_spread_mm, 0, count, holes) == 0) break;
    count = apply_filled(0, count, holes, zb);
  }
}

}  // namespace pipeloc
