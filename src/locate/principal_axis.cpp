#include "locate/principal_axis.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {

int count_sections(const ZBuffer& zb, const int* cells, int count, float theta, float min_w, float max_w,
                   AxisBuffers* buf) {
  // Scan lines run along (cos, sin); cells are binned into lines one cell apart and ordered
  // along each line, so consecutive keys of one line form runs.
  const float c = std::cos(theta), s = std::sin(theta);
  const int w = zb.z.width;
  const float p = float(zb.pixel_mm);
  std::int64_t* keys = buf->keys.data();
  for (int k = 0; k < count; ++k) {
    const float x = float(cells[k] % w), y = float(cells[k] / w);
    const std::int64_t line = round_nearest(-x * s + y * c) + (1 << 20);
    const std::int64_t along = round_nearest((x * c + y * s) * 4) + (1 << 24);  // quarter cells
    keys[k] = (line << 32) | along;
  }
  std::sort(keys, keys + count);
  int sections = 0;
  int k = 0;
  while (k < count) {
    int e = k;
    // A run continues while the next cell of the same line is at most 1.5 cells away.
    while (e + 1 < count && (keys[e + 1] >> 32) == (keys[k] >> 32) &&
           (keys[e + 1] & 0xffffffff) - (keys[e] & 0xffffffff) <= 6)
      ++e;
    const float width = (float((keys[e] & 0xffffffff) - (keys[k] & 0xffffffff)) / 4 + 1) * p;
    sections += width >= min_w && width <= max_w;
    k = e + 1;
  }
  return sections;
}

AxisEstimate estimate_axis(const ZBuffer& zb, const int* cells, int count,
                           const Eigen::Vector3f& core_centroid, const LocateConfig& cfg, float d,
                           AxisBuffers* buf) {
  AxisEstimate est;
  const float min_w = float(cfg.section_width_min_of_d) * d, max_w = float(cfg.section_width_max_of_d) * d;
  const float step = float(cfg.scan_step_deg * M_PI / 180.0);
  float best_theta = 0;
  // Coarse pass at twice the step, then the step either side of the best.
  for (float theta = 0; theta < float(M_PI) - 1e-4f; theta += 2 * step) {
    const int n = count_sections(zb, cells, count, theta, min_w, max_w, buf);
    if (n > est.best_count) est.best_count = n, best_theta = theta;
  }
  const float coarse = best_theta;
  for (const float theta : {coarse - step, coarse + step}) {
    const int n = count_sections(zb, cells, count, theta, min_w, max_w, buf);
    if (n > est.best_count) est.best_count = n, best_theta = theta;
  }
  est.scan_deg = float(best_theta * 180.0 / M_PI);
  // The scan direction with most pipe-wide sections is perpendicular to the axis.
  est.axis = Eigen::Vector2f(-std::sin(best_theta), std::cos(best_theta));
  // Initial position: the middle of the region's extent along the line through the core centroid.
  const int w = zb.z.width;
  float lo = 1e30f, hi = -1e30f, z_sum = 0;
  int near = 0;
  const Eigen::Vector2f c2 = core_centroid.head<2>();
  for (int k = 0; k < count; ++k) {
    const Eigen::Vector3f p = zb.point(cells[k] % w, cells[k] / w);
    const Eigen::Vector2f rel = p.head<2>() - c2;
    const float along = rel.dot(est.axis);
    const float across = rel.x() * -est.axis.y() + rel.y() * est.axis.x();
    if (std::abs(across) > d) continue;
    lo = std::min(lo, along), hi = std::max(hi, along);
    z_sum += p.z();
    ++near;
  }
  if (near == 0) lo = hi = 0;
  const Eigen::Vector2f mid = c2 + est.axis * (0.5f * (lo + hi));
  est.centre = Eigen::Vector3f(mid.x(), mid.y(), near ? z_sum / float(near) : core_centroid.z());
  return est;
}

}  // namespace pipeloc
