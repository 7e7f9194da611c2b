#include "locate/principal_axis.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {

void reserve_axis(AxisBuffers* buf, int max_cells, int w, int h) {
  buf->column.assign(std::size_t(max_cells), 0.0f);
  buf->row.assign(std::size_t(max_cells), 0.0f);
  buf->line.assign(std::size_t(max_cells), 0);
  buf->along.assign(std::size_t(max_cells), 0);
  buf->sorted.assign(std::size_t(max_cells), 0);
  buf->order.assign(std::size_t(max_cells), 0);
  buf->start.assign(std::size_t(w + h + 4), 0);           // lines cross the region: at most its diagonal
  buf->by_along.assign(std::size_t(4 * (w + h) + 8), 0);  // so do positions along them, in quarter cells
}

int count_sections(const float* column, const float* row, int count, float pixel_mm, float theta, float min_w,
                   float max_w, AxisBuffers* buf) {
  // Scan lines run along (cos, sin), one cell apart. Cells are ordered along the scan direction,
  // then grouped by line keeping that order (two counting sorts), so consecutive entries of a
  // line form runs.
  const float c = std::cos(theta), s = std::sin(theta);
  const float p = pixel_mm;
  int lmin = 1 << 30, lmax = -(1 << 30), amin = 1 << 30, amax = -(1 << 30);
  for (int k = 0; k < count; ++k) {
    const float x = column[k], y = row[k];
    const int line = int(round_nearest(-x * s + y * c));
    const int along = int(round_nearest((x * c + y * s) * 4));  // quarter cells
    buf->line[std::size_t(k)] = line;
    buf->along[std::size_t(k)] = along;
    lmin = std::min(lmin, line), lmax = std::max(lmax, line);
    amin = std::min(amin, along), amax = std::max(amax, along);
  }
  if (count == 0 || lmax - lmin + 2 > int(buf->start.size()) || amax - amin + 2 > int(buf->by_along.size()))
    return 0;
  // By position along the scan direction ...
  const int positions = amax - amin + 1;
  int* by_along = buf->by_along.data();
  std::fill_n(by_along, positions + 1, 0);
  for (int k = 0; k < count; ++k) ++by_along[buf->along[std::size_t(k)] - amin + 1];
  for (int a = 0; a < positions; ++a) by_along[a + 1] += by_along[a];
  for (int k = 0; k < count; ++k) buf->order[std::size_t(by_along[buf->along[std::size_t(k)] - amin]++)] = k;
  // ... then by line, in that order.
  const int lines = lmax - lmin + 1;
  int* start = buf->start.data();
  std::fill_n(start, lines + 1, 0);
  for (int k = 0; k < count; ++k) ++start[buf->line[std::size_t(k)] - lmin + 1];
  for (int l = 0; l < lines; ++l) start[l + 1] += start[l];
  for (int o = 0; o < count; ++o) {
    const int k = buf->order[std::size_t(o)];
    buf->sorted[std::size_t(start[buf->line[std::size_t(k)] - lmin]++)] = buf->along[std::size_t(k)];
  }
  // start[l] now ends line l: line l spans [start[l-1], start[l]).
  int sections = 0;
  for (int l = 0, b = 0; l < lines; b = start[l], ++l) {
    const int* a = buf->sorted.data() + b;
    const int n = start[l] - b;
    int k = 0;
    while (k < n) {
      int e = k;
      // A run continues while the next cell of the line is at most 1.5 cells away.
      while (e + 1 < n && a[e + 1] - a[e] <= 6) ++e;
      const float width = (float(a[e] - a[k]) / 4 + 1) * p;
      sections += width >= min_w && width <= max_w;
      k = e + 1;
    }
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
  // The cells' buffer coordinates, once for every scan direction.
  const int w = zb.z.width;
  const float pixel_mm = float(zb.pixel_mm);
  float *column = buf->column.data(), *row = buf->row.data();
  for (int k = 0; k < count; ++k) column[k] = float(cells[k] % w), row[k] = float(cells[k] / w);
  // Coarse pass at four times the step, then twice the step and the step either side of the
  // best (13 scans for 5 degrees instead of 36).
  for (float theta = 0; theta < float(M_PI) - 1e-4f; theta += 4 * step) {
    const int n = count_sections(column, row, count, pixel_mm, theta, min_w, max_w, buf);
    if (n > est.best_count) est.best_count = n, best_theta = theta;
  }
  for (const float delta : {2 * step, step}) {
    const float centre = best_theta;
    for (const float theta : {centre - delta, centre + delta}) {
      const int n = count_sections(column, row, count, pixel_mm, theta, min_w, max_w, buf);
      if (n > est.best_count) est.best_count = n, best_theta = theta;
    }
  }
  est.scan_deg = float(best_theta * 180.0 / M_PI);
  // The scan direction with most pipe-wide sections is perpendicular to the axis.
  est.axis = Eigen::Vector2f(-std::sin(best_theta), std::cos(best_theta));
  // Initial position: the middle of the region's extent along the line through the core centroid.
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
