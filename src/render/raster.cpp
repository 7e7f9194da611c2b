#include "render/raster.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

double edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double x, double y) {
  return (b.x() - a.x()) * (y - a.y()) - (b.y() - a.y()) * (x - a.x());
}

// An edge whose end points' rows differ by less than this (px) is taken as running along the
// row: it does not narrow a row's span (the exact test alone judges it).
constexpr double kRowEdgeMinRise = 1e-6;
// Triangles narrower than this (px) are scanned over their whole box: working out spans costs
// more than it saves.
constexpr int kSpanMinWidthPx = 8;

// The least and greatest of three (the first of equals, as std::min / std::max of a list, without
// the list's loop: the bounds are worked out for every face drawn).
double least_of(double a, double b, double c) {
  const double ab = b < a ? b : a;
  return c < ab ? c : ab;
}
double greatest_of(double a, double b, double c) {
  const double ab = a < b ? b : a;
  return ab < c ? c : ab;
}
// int(std::ceil(v)) and int(std::floor(v)) for v within int's range, from the truncation alone.
int ceil_to_int(double v) {
  const int t = int(v);
  return double(t) < v ? t + 1 : t;
}
int floor_to_int(double v) {
  const int t = int(v);
  return double(t) > v ? t - 1 : t;
}

// A scan's rows not wanted (on_row below).
struct NoRows {
  void operator()(int, int, int) const {}
};

// The rows of pixel centres a screen triangle's box spans in an image `height` rows high (none
// where y0 > y1).
struct ScanRows {
  int y0, y1;
};
ScanRows scan_rows(const Eigen::Vector2d& s0, const Eigen::Vector2d& s1, const Eigen::Vector2d& s2,
                   int height) {
  return {std::max(0, ceil_to_int(least_of(s0.y(), s1.y(), s2.y()))),
          std::min(height - 1, floor_to_int(greatest_of(s0.y(), s1.y(), s2.y())))};
}

// Visits the integer pixel centres inside the screen triangle s0 s1 s2 (either winding).
// A wide triangle's rows are scanned only over the span where the three edges' tests can hold (a
// long thin triangle lying across the image would otherwise be tested over its whole bounding
// box); the span is widened by a pixel each way, and every pixel in it takes the exact test, so
// the pixels visited are those of the test over the box. on_row(y, first, last) is told, once per
// row scanned, the columns scanned there (every pixel visited in the row lies among them).
// `rows`: scan_rows() of the triangle.
template <typename Visit, typename OnRow = NoRows>
void scan_triangle(const Eigen::Vector2d& s0, const Eigen::Vector2d& s1, const Eigen::Vector2d& s2, int width,
                   const ScanRows& rows, Visit visit, OnRow on_row = {}) {
  const double area = edge(s0, s1, s2.x(), s2.y());
  if (std::abs(area) < 1e-12) return;
  const double sign = area > 0 ? 1.0 : -1.0;
  const int x0 = std::max(0, ceil_to_int(least_of(s0.x(), s1.x(), s2.x())));
  const int x1 = std::min(width - 1, floor_to_int(greatest_of(s0.x(), s1.x(), s2.x())));
  const int y0 = rows.y0, y1 = rows.y1;
  const auto inside = [&](int x, int y) {
    return sign * edge(s1, s2, x, y) >= 0 && sign * edge(s2, s0, x, y) >= 0 && sign * edge(s0, s1, x, y) >= 0;
  };
  if (x1 - x0 < kSpanMinWidthPx) {
    for (int y = y0; y <= y1; ++y) {
      on_row(y, x0, x1);
      for (int x = x0; x <= x1; ++x)
        if (inside(x, y)) visit(x, y);
    }
    return;
  }
  // Along a row, edge a -> b's test holds on one side of x = a.x + (b.x - a.x) (y - a.y) / rise
  // (rise = b.y - a.y): at or beyond it where sign * rise < 0, up to it otherwise.
  struct Bound {
    double at_y0, per_row;
    bool lower;
  };
  Bound bounds[3];
  int n_bounds = 0;
  const Eigen::Vector2d* const edges[3][2] = {{&s1, &s2}, {&s2, &s0}, {&s0, &s1}};
  for (const auto& e : edges) {
    const Eigen::Vector2d &a = *e[0], &b = *e[1];
    const double rise = b.y() - a.y();
    if (std::abs(rise) < kRowEdgeMinRise) continue;
    const double per_row = (b.x() - a.x()) / rise;
    bounds[n_bounds++] = {a.x() + per_row * (y0 - a.y()), per_row, sign * rise < 0};
  }
  for (int y = y0; y <= y1; ++y) {
    double lo = x0, hi = x1;
    for (int i = 0; i < n_bounds; ++i) {
      const double root = bounds[i].at_y0 + bounds[i].per_row * (y - y0);
      if (bounds[i].lower)
        lo = std::max(lo, root);
      else
        hi = std::min(hi, root);
    }
    if (!(lo <= hi + 2)) continue;
    const int from = std::max(x0, int(std::floor(std::min(lo, double(x1)))) - 1);
    const int to = std::min(x1, int(std::ceil(std::max(hi, double(x0)))) + 1);
    on_row(y, from, to);
    for (int x = from; x <= to; ++x)
      if (inside(x, y)) visit(x, y);
  }
}

}  // namespace

void DepthTarget::reset(int width, int height) {
  z_mm.resize(width, height, 0.0f);
  label.resize(width, height, -1);
  normal.resize(width, height, Eigen::Vector3f::Zero());
}

namespace {

// Moves and projects every vertex; false if one lies behind or at the lens.
bool project_vertices(const Mesh& mesh, const Pose& model_to_cam, const Intrinsics& k, ProjectedMesh* out) {
  const Eigen::Matrix3d r = model_to_cam.linear();
  const Eigen::Vector3d t = model_to_cam.translation();
  bool in_front = true;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d p = r * mesh.vertices[i].cast<double>() + t;
    out->cam[i] = p;
    in_front = in_front && p.z() > 1;
    out->px[i] = p.z() > 1 ? k.project(p) : Eigen::Vector2d::Zero();
  }
  return in_front;
}

// Scan-converts the projected mesh; on_pixel(x, y, z, normal) for each covered pixel centre in
// the box, with the exact depth of the triangle's plane along that pixel's ray; on_row(y, first,
// last) for each row a face is scanned in, with the columns scanned (image coordinates).
// all_in_front: every vertex lies in front of the lens (project_vertices said so), no face is
// tested for it.
template <typename OnPixel, typename OnRow = NoRows>
void draw_perspective(const Mesh& mesh, const ProjectedMesh& pm, const Intrinsics& k, int x0, int y0, int x1,
                      int y1, Winding winding, bool all_in_front, OnPixel on_pixel, OnRow on_row = {}) {
  const Eigen::Vector2d corner(x0, y0);
  // A face is turned away when its outward normal points away from the camera (at the origin).
  const double away = winding == Winding::outward ? 1 : winding == Winding::inward ? -1 : 0;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d &p0 = pm.cam[f[0]], &p1 = pm.cam[f[1]], &p2 = pm.cam[f[2]];
    if (!all_in_front && (p0.z() <= 1 || p1.z() <= 1 || p2.z() <= 1)) continue;  // behind or at the lens
    Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    if (away * n.dot(p0) > 0) continue;
    // A face whose box spans no row of pixel centres draws nothing and is told to no row: left
    // before its plane is worked out (a welded tube's faces are a pixel or two across, many of
    // them between rows).
    const Eigen::Vector2d s0 = pm.px[f[0]] - corner, s1 = pm.px[f[1]] - corner, s2 = pm.px[f[2]] - corner;
    const ScanRows rows = scan_rows(s0, s1, s2, y1 - y0 + 1);
    if (rows.y0 > rows.y1) continue;
    const double length = n.norm();
    if (length < 1e-12) continue;
    n /= length;                // normalize(), its norm not worked out again
    if (n.dot(p0) > 0) n = -n;  // face the camera: depth images see either side
    const double plane = n.dot(p0);
    scan_triangle(
        s0, s1, s2, x1 - x0 + 1, rows,
        [&](int xr, int yr) {
          const int x = xr + x0, y = yr + y0;
          const Eigen::Vector3d ray((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1.0);
          const double denom = n.dot(ray);
          if (std::abs(denom) < 1e-9) return;
          const float z = float(plane / denom);
          if (z > 0) on_pixel(x, y, z, n);
        },
        [&](int yr, int first, int last) { on_row(yr + y0, first + x0, last + x0); });
  }
}

}  // namespace

void render_perspective(const Mesh& mesh, const Pose& model_to_cam, const Intrinsics& k, int label,
                        DepthTarget* target) {
  ProjectedMesh pm;
  pm.reserve(mesh);
  project_vertices(mesh, model_to_cam, k, &pm);
  draw_perspective(mesh, pm, k, 0, 0, target->z_mm.width - 1, target->z_mm.height - 1, Winding::open, false,
                   [&](int x, int y, float z, const Eigen::Vector3d& n) {
                     float& cur = target->z_mm.at(x, y);
                     if (cur == 0 || z < cur) {
                       cur = z;
                       target->label.at(x, y) = label;
                       target->normal.at(x, y) = n.cast<float>();
                     }
                   });
}

PixelBox render_depth_in_box(const Mesh& mesh, const Pose& model_to_cam, const Intrinsics& k,
                             Image<float>* z_mm, ProjectedMesh* pm, Winding winding) {
  PixelBox box;
  if (mesh.vertices.empty() || pm->cam.size() < mesh.vertices.size()) return box;
  if (!project_vertices(mesh, model_to_cam, k, pm)) return box;
  double lo_x = 1e30, lo_y = 1e30, hi_x = -1e30, hi_y = -1e30;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector2d& s = pm->px[i];
    lo_x = std::min(lo_x, s.x()), hi_x = std::max(hi_x, s.x());
    lo_y = std::min(lo_y, s.y()), hi_y = std::max(hi_y, s.y());
  }
  box.x0 = std::max(0, int(std::floor(lo_x)));
  box.y0 = std::max(0, int(std::floor(lo_y)));
  box.x1 = std::min(z_mm->width - 1, int(std::ceil(hi_x)));
  box.y1 = std::min(z_mm->height - 1, int(std::ceil(hi_y)));
  if (box.empty()) return box;
  for (int y = box.y0; y <= box.y1; ++y) std::fill_n(&z_mm->at(box.x0, y), box.x1 - box.x0 + 1, 0.0f);
  const bool keep_rows = pm->has_rows(z_mm->height);
  if (keep_rows) {
    std::fill(pm->row_first.begin() + box.y0, pm->row_first.begin() + box.y1 + 1, box.x1 + 1);
    std::fill(pm->row_last.begin() + box.y0, pm->row_last.begin() + box.y1 + 1, box.x0 - 1);
  }
  draw_perspective(
      mesh, *pm, k, box.x0, box.y0, box.x1, box.y1, winding, true,
      [&](int x, int y, float z, const Eigen::Vector3d&) {
        float& cur = z_mm->at(x, y);
        if (cur == 0 || z < cur) cur = z;
      },
      [&](int y, int first, int last) {
        if (!keep_rows) return;
        int &row_first = pm->row_first[std::size_t(y)], &row_last = pm->row_last[std::size_t(y)];
        row_first = std::min(row_first, first), row_last = std::max(row_last, last);
      });
  return box;
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
    const Eigen::Vector2d c0 = map->to_cell(p0.x(), p0.y()), c1 = map->to_cell(p1.x(), p1.y()),
                          c2 = map->to_cell(p2.x(), p2.y());
    scan_triangle(c0, c1, c2, map->z_mm.width, scan_rows(c0, c1, c2, map->z_mm.height), [&](int i, int j) {
      const double x = map->origin_x_mm + i * map->cell_mm;
      const double y = map->origin_y_mm + j * map->cell_mm;
      const float z = float((plane - n.x() * x - n.y() * y) / n.z());
      float& cur = map->z_mm.at(i, j);
      cur = top ? std::max(cur, z) : std::min(cur, z);
    });
  }
}

}  // namespace pipeloc
