#include "model/pipe_model.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numeric>
#include <random>
#include <unordered_map>

#include "model/neighbors.hpp"
#include "model/slides.hpp"
#include "model/stl.hpp"

namespace pipeloc {
namespace {

// Möller–Trumbore; returns distance along dir or -1.
float ray_triangle(const Eigen::Vector3f& o, const Eigen::Vector3f& d, const Eigen::Vector3f& a,
                   const Eigen::Vector3f& b, const Eigen::Vector3f& c) {
  const Eigen::Vector3f e1 = b - a, e2 = c - a;
  const Eigen::Vector3f p = d.cross(e2);
  const float det = e1.dot(p);
  if (std::abs(det) < 1e-12f) return -1;
  const float inv = 1.0f / det;
  const Eigen::Vector3f s = o - a;
  const float u = s.dot(p) * inv;
  if (u < -1e-6f || u > 1 + 1e-6f) return -1;
  const Eigen::Vector3f q = s.cross(e1);
  const float v = d.dot(q) * inv;
  if (v < -1e-6f || u + v > 1 + 1e-6f) return -1;
  return e2.dot(q) * inv;
}

// Hollow tubes: faces whose normals turn by less than this across a shared edge belong to one
// smooth surface (a tube of 6 sides turns by 60 degrees; a pipe end's rim by 90).
constexpr float kSmoothTurnDeg = 70;
// A smooth surface from whose faces no ray along the normal leaves the mesh (of this many tried,
// spread over it) and at least this share of the whole area is a bore the camera cannot see.
constexpr int kBoreProbes = 16;
constexpr float kBoreMinAreaShare = 0.1f;

// Whether a ray from the face's centre along its normal leaves the mesh without meeting a face.
bool escapes(const Mesh& mesh, std::size_t f) {
  const auto& t = mesh.faces[f];
  const Eigen::Vector3f c = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0f;
  const Eigen::Vector3f n = mesh.face_normal(f);
  const Eigen::Vector3f o = c + 1e-3f * n;
  for (std::size_t g = 0; g < mesh.faces.size(); ++g) {
    if (g == f) continue;
    const auto& u = mesh.faces[g];
    if (ray_triangle(o, n, mesh.vertices[u[0]], mesh.vertices[u[1]], mesh.vertices[u[2]]) > 0) return false;
  }
  return true;
}

int find_root(std::vector<int>* parent, int a) {
  while ((*parent)[a] != a) a = (*parent)[a] = (*parent)[(*parent)[a]];
  return a;
}

}  // namespace

Mesh without_bore(const Mesh& mesh, int* removed_faces) {
  *removed_faces = 0;
  const std::size_t nf = mesh.faces.size();
  // Smooth surfaces: faces joined across shared edges where their normals turn little.
  std::vector<int> parent(nf);
  std::iota(parent.begin(), parent.end(), 0);
  std::unordered_map<std::uint64_t, int> first_face;  // edge (lower, higher vertex) -> a face on it
  first_face.reserve(nf * 2);
  const float smooth = std::cos(kSmoothTurnDeg * float(M_PI) / 180.0f);
  for (std::size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
      const std::uint64_t key = (std::uint64_t(std::uint32_t(std::min(a, b))) << 32) | std::uint32_t(std::max(a, b));
      const auto [it, fresh] = first_face.emplace(key, int(f));
      if (fresh) continue;
      if (mesh.face_normal(f).dot(mesh.face_normal(std::size_t(it->second))) > smooth)
        parent[std::size_t(find_root(&parent, int(f)))] = find_root(&parent, it->second);
    }
  std::unordered_map<int, std::vector<int>> surfaces;
  for (std::size_t f = 0; f < nf; ++f) surfaces[find_root(&parent, int(f))].push_back(int(f));
  const float total = mesh.surface_area();
  std::vector<char> bore(nf, 0);
  for (const auto& [root, faces] : surfaces) {
    float area = 0;
    for (int f : faces) area += mesh.face_area(std::size_t(f));
    if (area < kBoreMinAreaShare * total || int(faces.size()) < kBoreProbes) continue;
    bool seen_from_outside = false;
    for (int p = 0; p < kBoreProbes && !seen_from_outside; ++p)
      seen_from_outside = escapes(mesh, std::size_t(faces[std::size_t(p) * faces.size() / kBoreProbes]));
    if (seen_from_outside) continue;
    for (int f : faces) bore[std::size_t(f)] = 1;
    *removed_faces += int(faces.size());
  }
  if (*removed_faces == 0 || *removed_faces == int(nf)) {
    *removed_faces = 0;
    return mesh;
  }
  Mesh out;
  std::vector<int> index(mesh.vertices.size(), -1);
  for (std::size_t f = 0; f < nf; ++f) {
    if (bore[f]) continue;
    std::array<int, 3> t{};
    for (int k = 0; k < 3; ++k) {
      int& v = index[std::size_t(mesh.faces[f][k])];
      if (v < 0) v = int(out.vertices.size()), out.vertices.push_back(mesh.vertices[std::size_t(mesh.faces[f][k])]);
      t[k] = v;
    }
    out.faces.push_back(t);
  }
  return out;
}

std::vector<Eigen::Vector3f> compute_vertex_normals(const Mesh& mesh) {
  std::vector<Eigen::Vector3f> normals(mesh.vertices.size(), Eigen::Vector3f::Zero());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    const Eigen::Vector3f n = mesh.face_normal(f) * mesh.face_area(f);
    for (int k = 0; k < 3; ++k) normals[t[k]] += n;
  }
  for (auto& n : normals) {
    const float len = n.norm();
    if (len > 0) n /= len;
  }
  return normals;
}

SurfaceSamples sample_surface(const Mesh& mesh, const std::vector<Eigen::Vector3f>& vn, int count,
                              unsigned seed) {
  std::vector<double> cumulative(mesh.faces.size());
  double sum = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) cumulative[f] = sum += mesh.face_area(f);
  SurfaceSamples out;
  if (sum <= 0 || count <= 0) return out;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  out.points.reserve(count);
  out.normals.reserve(count);
  for (int i = 0; i < count; ++i) {
    const double pick = uniform(rng) * sum;
    const std::size_t f = std::min<std::size_t>(
        std::lower_bound(cumulative.begin(), cumulative.end(), pick) - cumulative.begin(),
        mesh.faces.size() - 1);
    double u = uniform(rng), v = uniform(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const auto& t = mesh.faces[f];
    const float w0 = float(1 - u - v), w1 = float(u), w2 = float(v);
    out.points.push_back(w0 * mesh.vertices[t[0]] + w1 * mesh.vertices[t[1]] + w2 * mesh.vertices[t[2]]);
    Eigen::Vector3f n = w0 * vn[t[0]] + w1 * vn[t[1]] + w2 * vn[t[2]];
    if (n.norm() < 1e-6f) n = mesh.face_normal(f);
    out.normals.push_back(n.normalized());
  }
  return out;
}

std::vector<Eigen::Vector3f> spread_surface_points(const SurfaceSamples& surface, std::size_t count) {
  // The samples are drawn independently by area, so every stride-th of them is spread so too.
  const std::size_t stride =
      std::max<std::size_t>(1, surface.points.size() / std::max<std::size_t>(1, count));
  std::vector<Eigen::Vector3f> out;
  for (std::size_t i = 0; i < surface.points.size(); i += stride) out.push_back(surface.points[i]);
  return out;
}

float measure_tube_diameter(const Mesh& mesh, const std::vector<Eigen::Vector3f>& vn) {
  // On a swept tube the inward normal of a wall vertex passes through the centreline and meets
  // the opposite wall one diameter away; end caps and ring edges give outliers, hence the median.
  const std::size_t stride = std::max<std::size_t>(1, mesh.vertices.size() / 400);
  std::vector<float> widths;
  for (std::size_t i = 0; i < mesh.vertices.size(); i += stride) {
    const Eigen::Vector3f d = -vn[i];
    if (d.norm() < 0.5f) continue;
    const Eigen::Vector3f o = mesh.vertices[i] + 1e-3f * d;
    float best = -1;
    for (const auto& t : mesh.faces) {
      const float hit = ray_triangle(o, d, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
      if (hit > 1e-3f && (best < 0 || hit < best)) best = hit;
    }
    if (best > 0) widths.push_back(best + 1e-3f);
  }
  if (widths.empty()) return 0;
  std::nth_element(widths.begin(), widths.begin() + widths.size() / 2, widths.end());
  return widths[widths.size() / 2];
}

float longest_extent(const std::vector<Eigen::Vector3f>& v) {
  float best = 0;
  for (std::size_t i = 0; i < v.size(); ++i)
    for (std::size_t j = i + 1; j < v.size(); ++j) best = std::max(best, (v[i] - v[j]).squaredNorm());
  return std::sqrt(best);
}

Eigen::Matrix3d principal_axes(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& centroid) {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d d = (p - centroid).cast<double>();
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov /
                                                           double(std::max<std::size_t>(1, points.size())));
  return eig.eigenvectors();
}

Eigen::Vector3f centroid_of(const std::vector<Eigen::Vector3f>& points) {
  Eigen::Vector3f c = Eigen::Vector3f::Zero();
  for (const auto& p : points) c += p;
  return points.empty() ? c : Eigen::Vector3f(c / float(points.size()));
}

Pose turn_about(const Eigen::Vector3d& axis, const Eigen::Vector3f& centre, double angle) {
  Pose m = Pose::Identity();
  m.linear() = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
  m.translation() = centre.cast<double>() - m.linear() * centre.cast<double>();
  return m;
}

namespace {

// The half-turn about the line through `centre` along `axis`.
Pose half_turn(const Eigen::Vector3d& axis, const Eigen::Vector3f& centre) {
  return turn_about(axis, centre, M_PI);
}

// An exact symmetry lands this share of the samples on the surface (the rest: sharp edges).
constexpr float kSymmetryMinShare = 0.99f;
// Its refinement starts with pairs this many tolerances apart (12 x 0.08 D: about a diameter).
constexpr float kSymmetryGateStartOfTolerance = 12, kSymmetryGateEndOfTolerance = 6;

// What both half-turn searches start from: the surface's principal axes (the half-turns are
// about them) and its samples indexed for closest points.
struct IndexedSurface {
  Eigen::Matrix3d axes;
  KdTree3 tree;
  IndexedSurface(const SurfaceSamples& surface, const Eigen::Vector3f& centroid)
      : axes(principal_axes(surface.points, centroid)) {
    tree.build(surface.points.data(), surface.points.size());
  }
};

}  // namespace

namespace {

// A half-turn about a principal axis, refined on the part of the surface it maps onto itself:
// pairs are gated from `gate_start_mm` down to `gate_end_mm`, so that parts that differ do not
// pull and sampling noise in the principal axes (a degree or so) is taken out.
Pose refine_half_turn(const SurfaceSamples& surface, const IndexedSurface& indexed,
                      const Eigen::Vector3f& centroid, int axis, std::size_t stride, float gate_start_mm,
                      float gate_end_mm) {
  Pose m = half_turn(indexed.axes.col(axis), centroid);
  const std::size_t n = (surface.points.size() + stride - 1) / stride;
  float reach_mm = 0;  // the samples' farthest distance from the origin of the model frame
  for (std::size_t i = 0; i < n; ++i) reach_mm = std::max(reach_mm, surface.points[i * stride].norm());
  // Point-to-plane steps (the samples' normals): a leg mapped onto another slides into place in a
  // few steps, where point-to-point pairs move it a little at a time. The gate narrows over the
  // first iterations.
  constexpr int kNarrowing = 6, kMaxIterations = 20;
  constexpr double kConvergedMm = 0.002;
  for (int iter = 0; iter < kMaxIterations; ++iter) {
    const float t = std::min(1.0f, float(iter) / float(kNarrowing));
    const float gate = gate_start_mm + (gate_end_mm - gate_start_mm) * t;
    Eigen::Matrix<double, 6, 6> ata = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> atb = Eigen::Matrix<double, 6, 1>::Zero();
    int pairs = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d q = m * surface.points[i * stride].cast<double>();
      int idx = 0;
      float d2 = 0;
      if (!indexed.tree.nearest_within(q.cast<float>(), gate, &idx, &d2)) continue;
      const Eigen::Vector3d s = surface.points[std::size_t(idx)].cast<double>();
      const Eigen::Vector3d nrm = surface.normals[std::size_t(idx)].cast<double>();
      Eigen::Matrix<double, 6, 1> row;
      row << q.cross(nrm), nrm;
      ata += row * row.transpose();
      atb -= row * (q - s).dot(nrm);
      ++pairs;
    }
    if (pairs < 10) break;
    const Eigen::Matrix<double, 6, 1> x = ata.ldlt().solve(atb);
    if (!x.allFinite()) break;
    Pose step = Pose::Identity();
    const double angle = x.head<3>().norm();
    if (angle > 0) step.linear() = Eigen::AngleAxisd(angle, x.head<3>() / angle).toRotationMatrix();
    step.translation() = x.tail<3>();
    m = step * m;
    m.linear() = nearest_rotation(m.linear());
    // How far the step moved a sample at most: the turn times the part's reach, plus the shift.
    const double moved = x.tail<3>().norm() + angle * double(reach_mm);
    if (iter >= kNarrowing && moved < kConvergedMm) break;
  }
  return m;
}

// How far each sample lands from the surface under `m`: the least point-to-plane distance to the
// samples around where it lands (one sample's plane is wrong at a sharp edge, e.g. an end cap's
// rim, and the gap between samples is no departure from the surface). Returns the share of
// samples within tolerance_mm and the largest distance to the nearest sample (infinite once a
// sample lands farther than gap_mm from every sample: the search stops there).
struct LandingShare {
  float within = 0;
  float worst_gap_mm = 0;
};
LandingShare landing_share(const SurfaceSamples& surface, const IndexedSurface& indexed, const Pose& m,
                           std::size_t stride, float tolerance_mm, float spacing_mm, float gap_mm) {
  constexpr int kAround = 8;
  int idx[kAround];
  float d2[kAround];
  const float radius = tolerance_mm + 2 * spacing_mm;
  const std::size_t n = (surface.points.size() + stride - 1) / stride;
  int within = 0;
  LandingShare out;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f q = (m * surface.points[i * stride].cast<double>()).cast<float>();
    // Farther than `gap_mm` from every sample the search stops: that alone fails the symmetry.
    int nearest = 0;
    float nearest_d2 = 0;
    const bool landed = indexed.tree.nearest_within(q, gap_mm, &nearest, &nearest_d2);
    out.worst_gap_mm = std::max(out.worst_gap_mm, std::sqrt(nearest_d2));
    if (!landed) continue;  // off every sample: not within
    float best =
        std::abs((q - surface.points[std::size_t(nearest)]).dot(surface.normals[std::size_t(nearest)]));
    const int found = indexed.tree.radius(q, radius, idx, d2, kAround);
    for (int k = 0; k < found; ++k)
      best = std::min(
          best,
          std::abs((q - surface.points[std::size_t(idx[k])]).dot(surface.normals[std::size_t(idx[k])])));
    within += std::sqrt(nearest_d2) <= radius && best <= tolerance_mm;
  }
  out.within = float(within) / float(std::max<std::size_t>(1, n));
  return out;
}

}  // namespace

std::vector<Pose> find_symmetries(const SurfaceSamples& surface, const Eigen::Vector3f& centroid,
                                  float tolerance_mm, float spacing_mm) {
  // A rigid symmetry fixes the surface centroid and maps principal axes onto principal axes; with
  // distinct principal moments the only proper candidates are half-turns about each axis.
  std::vector<Pose> found;
  if (surface.points.size() < 10) return found;
  const IndexedSurface indexed(surface, centroid);
  const std::size_t stride = std::max<std::size_t>(1, surface.points.size() / 3000);
  // The refinement starts a tube diameter wide (the tolerance is a share of it): the principal
  // axes of a long thin part tilt by a degree with sampling noise, millimetres at its ends.
  const float gate_start = kSymmetryGateStartOfTolerance * tolerance_mm + 2 * spacing_mm;
  // ... and ends half as wide: the pairs of an exact symmetry all come close, and keeping the far
  // ones (a leg's end a few mm off) pulls it in; a part that only nearly maps onto itself is
  // pulled askew by them and fails the landing test below, as it should.
  const float gate_end = kSymmetryGateEndOfTolerance * tolerance_mm + spacing_mm;
  for (int axis = 0; axis < 3; ++axis) {
    const Pose m = refine_half_turn(surface, indexed, centroid, axis, stride, gate_start, gate_end);
    // Every sample must land on the surface, but for the few at sharp edges (end caps' rims)
    // where the samples' own planes are a mesh-discretisation artefact.
    const float max_gap_mm = tolerance_mm + 4 * spacing_mm;
    const LandingShare share =
        landing_share(surface, indexed, m, stride, tolerance_mm, spacing_mm, max_gap_mm);
    if (share.within < kSymmetryMinShare || share.worst_gap_mm > max_gap_mm) continue;
    Pose refined = m;
    refined.linear() = nearest_rotation(refined.linear());
    // A refinement that slid to the identity is not a symmetry, nor one that slid to a symmetry
    // already found (from another axis: the in-plane axes of a flat part can turn into each other).
    if (rotation_angle_deg(Eigen::Matrix3d::Identity(), refined.linear()) <= 90) continue;
    bool known = false;
    for (const Pose& f : found) known = known || rotation_angle_deg(f.linear(), refined.linear()) < 10;
    if (!known) found.push_back(refined);
  }
  return found;
}

std::vector<Pose> find_near_symmetries(const SurfaceSamples& surface, const Eigen::Vector3f& centroid,
                                       float tolerance_mm, float min_share, const std::vector<Pose>& exclude,
                                       float exclude_mm, const std::vector<Pose>& starts) {
  std::vector<Pose> found;
  if (surface.points.size() < 10) return found;
  const IndexedSurface indexed(surface, centroid);
  const std::size_t stride = std::max<std::size_t>(1, surface.points.size() / 1000);
  const std::size_t n = (surface.points.size() + stride - 1) / stride;
  // Largest displacement of a sample between two transforms.
  const auto displacement = [&](const Pose& a, const Pose& b) {
    float worst = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d p = surface.points[i * stride].cast<double>();
      worst = std::max(worst, float((a * p - b * p).norm()));
    }
    return worst;
  };
  for (std::size_t start = 0; start < 3 + starts.size(); ++start) {
    Pose m = start < 3 ? half_turn(indexed.axes.col(int(start)), centroid) : starts[start - 3];
    // Refined on the part it maps onto itself: pairs are gated, from a tube diameter's worth of
    // distance (4 tolerances) down to the tolerance, so the parts that differ do not pull.
    float share = 0;
    for (int iter = 0; iter < 8; ++iter) {
      const float gate = tolerance_mm * std::max(1.0f, 4.0f - float(iter));
      Eigen::Matrix3Xd src(3, Eigen::Index(n)), dst(3, Eigen::Index(n));
      Eigen::Index pairs = 0;
      int within = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f& p = surface.points[i * stride];
        const Eigen::Vector3f q = (m * p.cast<double>()).cast<float>();
        int idx = 0;
        float d2 = 0;
        if (!indexed.tree.nearest_within(q, gate, &idx, &d2)) continue;  // gate >= tolerance_mm
        within += d2 <= tolerance_mm * tolerance_mm;
        if (d2 > gate * gate) continue;
        src.col(pairs) = p.cast<double>();
        dst.col(pairs) = surface.points[std::size_t(idx)].cast<double>();
        ++pairs;
      }
      share = float(within) / float(n);
      if (pairs < 10) break;
      m.matrix() = Eigen::umeyama(src.leftCols(pairs), dst.leftCols(pairs), false);
      m.linear() = nearest_rotation(m.linear());
    }
    if (share < min_share || rotation_angle_deg(Eigen::Matrix3d::Identity(), m.linear()) <= 90) continue;
    bool known = false;
    for (const Pose& e : exclude) known = known || displacement(e, m) <= exclude_mm;
    for (const Pose& e : found) known = known || displacement(e, m) <= exclude_mm;
    if (!known) found.push_back(m);
  }
  return found;
}

void orient_outward(Mesh* mesh) {
  // Exporters disagree on winding; a closed surface wound outward encloses positive volume.
  double volume6 = 0;
  const Eigen::Vector3f ref = mesh->vertices[0];
  for (const auto& t : mesh->faces)
    volume6 += double(
        (mesh->vertices[t[0]] - ref).dot((mesh->vertices[t[1]] - ref).cross(mesh->vertices[t[2]] - ref)));
  if (volume6 < 0)
    for (auto& t : mesh->faces) std::swap(t[1], t[2]);
}

PipeModel derive_pipe_model(Mesh mesh, const std::string& source, const ModelDerivation& params) {
  PipeModel model;
  model.source = source;
  model.mesh = std::move(mesh);
  if (model.mesh.faces.empty()) throw ModelError("model '" + source + "': mesh has no triangles");
  orient_outward(&model.mesh);
  // Beyond the paper: a real pipe's STL often models its bore; the camera sees the outer surface.
  model.mesh = without_bore(model.mesh, &model.bore_faces_removed);
  model.vertex_normals = compute_vertex_normals(model.mesh);
  const float area = model.mesh.surface_area();
  if (!(area > 0) || !std::isfinite(area)) throw ModelError("model '" + source + "': surface area is zero");
  // Clamped before the conversion: an area of 1e12 mm^2 times the density is beyond int (fuzz).
  const int count = int(std::clamp(double(area) * params.samples_per_mm2, 100.0, double(params.max_samples)));
  model.surface = sample_surface(model.mesh, model.vertex_normals, count, params.seed);
  model.centroid = centroid_of(model.surface.points);
  model.tube_diameter_mm = measure_tube_diameter(model.mesh, model.vertex_normals);
  model.extent_mm = longest_extent(model.mesh.vertices);
  if (!(model.tube_diameter_mm > 0) || model.tube_diameter_mm >= model.extent_mm)
    throw ModelError("model '" + source + "': cannot measure a tube diameter (is it a closed tube?)");
  // A tube under a millimetre is no pipe a depth sensor sees: most likely the STL is in metres.
  constexpr float kMinTubeMm = 1.0f;
  if (model.tube_diameter_mm < kMinTubeMm)
    throw ModelError("model '" + source + "': tube diameter " + std::to_string(model.tube_diameter_mm) +
                     " mm, under 1 mm: the STL must be in millimetres (is it in metres?)");
  // A pipe longer than 3 m fits in no bin a depth sensor sees whole, and the localizer's buffers
  // grow with L^2 (its ridge grid alone is (L / 2 mm)^2 cells): a 50 m model asks for tens of GB.
  // Most likely the STL is in tenths of a millimetre or micrometres.
  constexpr float kMaxExtentMm = 3000.0f;
  if (model.extent_mm > kMaxExtentMm)
    throw ModelError("model '" + source + "': longest extent L " + std::to_string(int(model.extent_mm)) +
                     " mm, beyond 3000 mm: the STL must be in millimetres (is it in 1/10 mm or um?)");
  model.symmetry_tolerance_mm = params.symmetry_tolerance_of_diameter * model.tube_diameter_mm;
  // The samples' spacing: a mapped sample lands between samples, up to this far from the nearest.
  const float spacing_mm = std::sqrt(area / float(model.surface.points.size()));
  model.symmetries = find_symmetries(model.surface, model.centroid, model.symmetry_tolerance_mm, spacing_mm);
  // Besides the half-turns about the principal axes: the centreline reversed about the middle of
  // the part its two ends share (a U with legs of 378 and 118 mm: its principal axes lie askew
  // of its symmetry, and the refinement does not reach it from there).
  const std::vector<Pose> reversal = {best_reversal(centreline_of(model.surface, model.tube_diameter_mm))};
  model.near_symmetries = find_near_symmetries(
      model.surface, model.centroid, params.near_symmetry_tolerance_of_diameter * model.tube_diameter_mm,
      params.near_symmetry_min_share, model.symmetries, model.tube_diameter_mm, reversal);
  for (const Pose& m : model.near_symmetries)
    model.near_symmetry_spread.push_back(surface_spread(model.surface, m, spacing_mm));
  return model;
}

PipeModel::Spread surface_spread(const SurfaceSamples& surface, const Pose& motion, float spacing_mm) {
  PipeModel::Spread out;
  if (surface.points.empty()) return out;
  KdTree3 tree;
  tree.build(surface.points.data(), surface.points.size());
  const std::size_t stride = std::max<std::size_t>(1, surface.points.size() / 4000);
  std::vector<float> d;
  for (std::size_t i = 0; i < surface.points.size(); i += stride) {
    const Eigen::Vector3f q = (motion * surface.points[i].cast<double>()).cast<float>();
    int idx = 0;
    float d2 = 0;
    if (!tree.nearest(q, &idx, &d2)) continue;
    const std::size_t k = std::size_t(idx);
    const Eigen::Vector3f off = q - surface.points[k];
    const float across = surface.normals[k].dot(off);
    const float along = std::max(0.0f, (off - across * surface.normals[k]).norm() - spacing_mm);
    d.push_back(std::sqrt(across * across + along * along));
  }
  if (d.empty()) return out;
  std::sort(d.begin(), d.end());
  out.p95_mm = d[std::size_t(0.95 * double(d.size() - 1))];
  out.max_mm = d.back();
  return out;
}

std::string describe_near_symmetries(const PipeModel& model) {
  if (model.near_symmetries.empty()) return "no near symmetry (no pose has a twin to tell apart)";
  const std::size_t n = model.near_symmetries.size();
  std::string out =
      std::to_string(n) + (n == 1 ? " near symmetry (a half-turn that swaps its ends): the twin's"
                                  : " near symmetries (half-turns that swap its ends): each twin's");
  out += " surface lies within";
  for (std::size_t k = 0; k < model.near_symmetry_spread.size(); ++k) {
    char text[96];
    std::snprintf(text, sizeof text, "%s %.1f mm of the pipe's over 95 %% of it, %.1f mm everywhere",
                  k ? ";" : "", double(model.near_symmetry_spread[k].p95_mm),
                  double(model.near_symmetry_spread[k].max_mm));
    out += text;
  }
  return out + ". Where a view does not resolve that, the pose is AMBIGUOUS (not handed out)";
}

namespace {

// The spread everywhere of the near twin nearest the pipe (infinity without one).
double nearest_twin_spread_mm(const PipeModel& model) {
  double nearest_mm = std::numeric_limits<double>::infinity();
  for (const PipeModel::Spread& s : model.near_symmetry_spread)
    nearest_mm = std::min(nearest_mm, double(s.max_mm));
  return nearest_mm;
}

// The distance (mm) from the camera where `pixels` pixels' footprint spans `spread_mm`.
double spanned_within_mm(double spread_mm, double fx_px, double pixels) { return spread_mm * fx_px / pixels; }

}  // namespace

double twin_resolved_within_mm(const PipeModel& model, double fx_px, double pixels) {
  return spanned_within_mm(nearest_twin_spread_mm(model), fx_px, pixels);
}

std::string describe_twin_resolution(const PipeModel& model, double fx_px, bool poses_withheld) {
  if (model.near_symmetry_spread.empty() || !(fx_px > 0)) return "";
  const double spread_mm = nearest_twin_spread_mm(model);
  char text[320];
  std::snprintf(
      text, sizeof text,
      "this camera (fx %.0f px) resolves the near twin nearer than %.2f m, where %.0f pixels cover its "
      "%.1f mm spread; farther, the image may not tell the pipe's ends apart: its poses stay AMBIGUOUS or "
      "a pick may be the pipe turned end for end (mount the camera nearer where the ends differ)",
      fx_px, spanned_within_mm(spread_mm, fx_px, kTwinResolvedPixels) / 1000.0, kTwinResolvedPixels,
      spread_mm);
  std::string out = text;
  if (poses_withheld) {
    std::snprintf(text, sizeof text,
                  "; farther than %.2f m, where one pixel covers it, no pose is handed out (AMBIGUOUS)",
                  spanned_within_mm(spread_mm, fx_px, kTwinUnresolvedPixels) / 1000.0);
    out += text;
  }
  return out;
}

PipeModel load_pipe_model(const std::string& stl_path, const ModelDerivation& params) {
  return derive_pipe_model(read_stl(stl_path), stl_path, params);
}

}  // namespace pipeloc
