// What the localizer needs to know about a pipe, derived from its mesh alone (DESIGN: "Model
// inputs (tube diameter, longest extent L) are derived from the STL itself").
#pragma once

#include <string>
#include <vector>

#include "core/pose.hpp"
#include "model/mesh.hpp"

namespace pipeloc {

struct SurfaceSamples {
  std::vector<Eigen::Vector3f> points;   // model frame, mm
  std::vector<Eigen::Vector3f> normals;  // outward, unit
};

struct PipeModel {
  std::string source;  // file or preset it came from
  Mesh mesh;
  std::vector<Eigen::Vector3f> vertex_normals;
  SurfaceSamples surface;      // about one sample per mm^2
  float tube_diameter_mm = 0;  // R of the paper
  int bore_faces_removed = 0;  // faces of the bore of a hollow STL, taken out (without_bore)
  float extent_mm = 0;         // L of the paper: longest distance between two vertices
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  // of the surface
  std::vector<Pose> symmetries;  // proper rotations other than identity mapping the surface onto itself
  float symmetry_tolerance_mm = 0;
  // Half-turns that map most of the surface onto itself but not all of it (the ends of a pipe
  // swapped): a view of the part that shows only the common surface fits both poses.
  std::vector<Pose> near_symmetries;
  // For each near symmetry, how far its surface lies from the pipe's: what a camera must resolve
  // to tell the two apart (an integrator's figure; the localizer judges each view by its pixels).
  struct Spread {
    float p95_mm = 0, max_mm = 0;
  };
  std::vector<Spread> near_symmetry_spread;
};

struct ModelDerivation {
  float samples_per_mm2 = 1.0f;
  int max_samples = 40000;
  unsigned seed = 1;
  // A candidate rotation is a symmetry when no surface sample lands further than this from the
  // surface; as a share of the tube diameter (so it scales with the part).
  float symmetry_tolerance_of_diameter = 0.08f;
  // A half-turn is a near symmetry when at least this share of the surface lands within
  // near_symmetry_tolerance_of_diameter * D of the surface (and it is no symmetry).
  float near_symmetry_min_share = 0.6f;
  float near_symmetry_tolerance_of_diameter = 0.25f;
};

PipeModel derive_pipe_model(Mesh mesh, const std::string& source, const ModelDerivation& = {});
PipeModel load_pipe_model(const std::string& stl_path, const ModelDerivation& = {});

// Area-weighted surface samples with interpolated vertex normals, deterministic for a seed.
SurfaceSamples sample_surface(const Mesh& mesh, const std::vector<Eigen::Vector3f>& vertex_normals, int count,
                              unsigned seed);
std::vector<Eigen::Vector3f> compute_vertex_normals(const Mesh& mesh);
// About `count` of the surface samples, spread over the surface by area: for the share of a pipe
// somewhere (out of the view, below the floor), which the mesh's vertices do not give (a straight
// piece has vertices only at its ends, a bend many along it).
std::vector<Eigen::Vector3f> spread_surface_points(const SurfaceSamples& surface, std::size_t count);
// Flips the winding if the surface encloses negative volume, so face normals point outward.
void orient_outward(Mesh* mesh);

// Median distance from a vertex straight through the tube to the opposite wall.
float measure_tube_diameter(const Mesh& mesh, const std::vector<Eigen::Vector3f>& vertex_normals);

// The mesh without the bore of a hollow pipe: a smooth surface (normals turning by less than 70
// degrees across its edges) of at least a tenth of the area from which no ray along the normal
// leaves the mesh. A solid pipe comes back unchanged. removed_faces: how many were taken out.
Mesh without_bore(const Mesh& mesh, int* removed_faces);
float longest_extent(const std::vector<Eigen::Vector3f>& vertices);
// The turn by `angle` (rad) about the line through `centre` along `axis`.
Pose turn_about(const Eigen::Vector3d& axis, const Eigen::Vector3f& centre, double angle);
// The mean of a point set (zero for none).
Eigen::Vector3f centroid_of(const std::vector<Eigen::Vector3f>& points);
// Principal axes of a point set about `centroid`: the columns, by increasing spread.
Eigen::Matrix3d principal_axes(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& centroid);
// The half-turns about the principal axes that land (all but a sharp edge's share of) the samples
// within tolerance_mm of the surface; spacing_mm is the samples' spacing (mesh discretisation).
std::vector<Pose> find_symmetries(const SurfaceSamples& surface, const Eigen::Vector3f& centroid,
                                  float tolerance_mm, float spacing_mm);
// The half-turns about the principal axes, and the motions in `starts`, each refined on the
// surface it maps onto itself, that bring at least min_share of the samples within tolerance_mm of
// the surface; those within `exclude_mm` (largest sample displacement) of one of `exclude` or of
// one found before are left out.
std::vector<Pose> find_near_symmetries(const SurfaceSamples& surface, const Eigen::Vector3f& centroid,
                                       float tolerance_mm, float min_share, const std::vector<Pose>& exclude,
                                       float exclude_mm, const std::vector<Pose>& starts = {});
// How far the surface moved by `motion` lies from the surface: its 95th percentile and its
// largest. Point to plane at the nearest sample, where the two lie within the samples' spacing
// along the surface (so the spacing does not count), beyond that the distance past it.
PipeModel::Spread surface_spread(const SurfaceSamples& surface, const Pose& motion, float spacing_mm);
// One line for the start-up log: the near symmetries and how far each lies from the pipe.
std::string describe_near_symmetries(const PipeModel& model);
// A near twin whose surface lies within about this many pixels' footprint of the pipe's
// everywhere was mostly not told apart on the zoo: 23-planar (0.9 px) and 05-elbow (1.4 px) of
// seed 21 stayed ambiguous or were handed out turned end for end; at 2.1-2.7 px (11-S-asym,
// 04-elbow) the bins cleared (docs/experiments.md, "Near twins the view cannot resolve").
constexpr double kTwinResolvedPixels = 2.0;
// ... and where one pixel's footprint covers that spread, no pixel can show it at all: the
// localizer's twin_beyond_resolution_ambiguous.
constexpr double kTwinUnresolvedPixels = 1.0;
// How far from the camera (mm) `pixels` pixels' footprint (distance / fx_px each) stays within the
// nearest near twin's spread everywhere: nearer, the camera resolves the twin; farther, it may not.
// Infinity without a near symmetry.
double twin_resolved_within_mm(const PipeModel& model, double fx_px, double pixels = kTwinResolvedPixels);
// One line for the start-up log with the camera's focal length: that distance, for the integrator
// choosing how high to mount the camera, and with poses_withheld the distance beyond which the
// localizer hands out none ("" without a near symmetry).
std::string describe_twin_resolution(const PipeModel& model, double fx_px, bool poses_withheld);

}  // namespace pipeloc
