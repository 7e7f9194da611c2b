// What the localizer precomputes from a pipe model at start-up: its frame (principal axis, the
// side that faces up when it lies flat), ridge samples, and a voxel index of its surface for
// O(1) closest-point look-ups during refinement.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "locate/zridge.hpp"
#include "model/pipe_model.hpp"

namespace pipeloc {

struct LocatorModel {
  const PipeModel* model = nullptr;
  Eigen::Vector3f axis = Eigen::Vector3f::UnitX();  // direction of largest spread (model frame)
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();    // direction of least spread
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  std::vector<Eigen::Vector3f> ridge_samples;  // subset of surface samples for the Z-ridge
  std::vector<Eigen::Vector3f> ridge_normals;  // their outward normals
  // The same by coordinate, one set per stride a ridge cell of the config takes them with.
  std::vector<OrientedColumns> ridge_columns;
  const OrientedColumns* ridge_columns_for(int stride) const {
    for (const auto& c : ridge_columns)
      if (c.stride == stride) return &c;
    return nullptr;
  }
  std::vector<Eigen::Vector3f> check_points;  // vertices spread over the part, for pose distances
  // Points along the tube's centreline (model/slides.hpp), for pick distances: a pipe turned
  // about its own straight axis is the same pick. Empty when no centreline was found.
  std::vector<Eigen::Vector3f> centreline_points;
  float centreline_step_mm = 0;  // ... their spacing along it (the last may be nearer)
  // A straight tube (its centreline within D/10 of a line): turned about its own axis it is the
  // same, and the ridge ICP leaves that turn out (locate/rigid_fit.hpp).
  bool straight = false;
  // ... that slides along itself (slides not empty): what decide() takes for a straight tube
  // (Evidence::model_straight), and the service's log with it.
  bool slides_as_straight_tube() const { return straight && !slides.empty(); }
  // The mesh verification renders: vertices merged on a grid of D/8 (within a pixel's footprint at
  // the bin's depth, several times fewer triangles to draw per hypothesis).
  Mesh verify_mesh;
  // How the model's faces wind if it is closed; the merged mesh keeps each face's winding.
  Winding verify_winding = Winding::open;
  float tube_d_mm = 0, extent_l_mm = 0;
  // How far an initial state may be slid to cover a partial view: across the principal axis,
  // half the model's width beside the tube (one leg of a U onto the other); along it, L/4.
  float slide_across_mm = 0, slide_along_mm = 0;

  // IV-B initial states, one per turn about the axis: the model lying turned by 360/turns * k,
  // placed so that its principal direction measured by III (the same cross-section count as on
  // the observed region, on its own top view) lies along +X and its measured centre at the origin.
  std::vector<Pose> canonical_starts;
  // Beyond the paper: the model's slides along itself (model/slides.hpp) by more than the
  // ambiguity distance; the pose found, slid, is judged as a rival (off: judge_slides = false).
  // The first short_slides move it up to five steps; the others, far along it (a coil a third of
  // a turn round its helix), as far as its near-symmetry share leaves it on itself.
  std::vector<Pose> slides;
  // ... and slides of D/12 to D both ways, which place a pose its ends pin (place_slides_finely).
  std::vector<Pose> fine_slides;
  // ... and slides of D, 2 D, ... both ways as far as the far slides reach, along which a pose
  // the tube goes on beyond is followed to where the image shows its end (follow_slides_to_ends).
  std::vector<Pose> follow_slides;
  std::size_t short_slides = 0;
  // Beyond the paper: turns about the centreline's principal axis through its centroid (none for a
  // straight tube, whose turn about its axis is the same pick). A short or nearly straight pipe's
  // top strip tells its turn about its own length least: the refinement keeps the turn it started
  // from (the 8.4 mm elbow's and the 16.7 mm S's poses 5-12 mm off are turned 20-140 degrees about
  // it). Where a quarter turn lands near_symmetry_min_share of the surface within the near
  // symmetries' tolerance of itself (short bends, short S and Z: the zoo's elbows 0.67-0.93), in
  // eighths: a thin S's pose turned 42 degrees, 13 mm off, was handed out while its quarter turns
  // refined back to it (seed 21's 11-S-asym). Elsewhere in quarters; and none for a pipe that
  // slides along itself (an arc's or a coil's quarter turn lands 0.45 and less), which turned
  // slides onto poses as good and which its ends place (seed 19's 18-coil: 3 -> 0 of its bin taken).
  std::vector<Pose> rolls;
  static constexpr std::size_t kMostRolls = 7;  // eighth turns
  // Beyond the paper: the principal direction of a partly hidden curved pipe can be far from that
  // of the whole model, so each start is also turned about the vertical, in steps covering half a
  // turn (the reversed direction covers the other half).
  int yaw_offsets = 1;
  double yaw_step_rad = 0;
  double yaw_offset_rad(int y) const { return (y - yaw_offsets / 2) * yaw_step_rad; }

  // Voxel index: nearest surface sample of each voxel centre within `margin` of the surface.
  // Compact, for the refinement's cache: two bytes a voxel, naming a sample whose point and normal
  // lie side by side.
  struct Sample {
    Eigen::Vector3f p, n;  // model frame; outward
  };
  static constexpr std::uint16_t kNoSample = 0xffff;  // further than the margin
  Eigen::Vector3f voxel_origin = Eigen::Vector3f::Zero();
  // A power of two: the lookup's division by it is a multiplication, exactly.
  static constexpr float voxel_mm = 2;
  int nx = 0, ny = 0, nz = 0;
  std::vector<std::uint16_t> voxel_sample;  // into samples
  std::vector<Sample> samples;              // those some voxel names, in surface-sample order
  // Per sample, the tube's direction there (unit, square to n; the centreline's nearest step),
  // zero where no centreline was found: the tube round a sample read as a cylinder. Only with
  // refine_ray_pairs (else empty); beside the samples, not in them: the look-ups stay as small.
  std::vector<Eigen::Vector3f> sample_directions;

  const Sample* nearest_sample(const Eigen::Vector3f& p_model) const {
    const Eigen::Vector3f g = (p_model - voxel_origin) / voxel_mm;
    const int i = int(g.x()), j = int(g.y()), k = int(g.z());
    if (g.x() < 0 || g.y() < 0 || g.z() < 0 || i >= nx || j >= ny || k >= nz) return nullptr;
    const std::uint16_t s = voxel_sample[(std::size_t(k) * ny + j) * nx + i];
    return s == kNoSample ? nullptr : &samples[s];
  }
};

struct LocateConfig;
struct AxisEstimate;
LocatorModel prepare_locator_model(const PipeModel& model, float margin_mm, const LocateConfig& cfg);

// Coarser ridge cells need proportionally fewer samples: every this-many-th, the same few per cell.
int ridge_sample_stride(float cell_mm, const LocateConfig& cfg);

// III applied to the model's ideal top view at model_to_bin (the whole silhouette, no noise).
AxisEstimate top_view_axis(const PipeModel& model, const Pose& model_to_bin, const LocateConfig& cfg);

// How far apart two poses put the tube's centreline (the pick), the model's symmetries taken into
// account; pose_distance_mm where no centreline was found. Beyond bound_mm, some value beyond it.
float pick_distance_mm(const LocatorModel& lm, const Pose& a, const Pose& b, float bound_mm);
// Largest distance of the check points between two poses, minimised over the model's symmetries.
// Exact up to `bound_mm`; a distance beyond it may be cut short, returning some value beyond it
// (a caller comparing with bound_mm gets the same answer, sooner).
float pose_distance_mm(const LocatorModel& lm, const Pose& a, const Pose& b,
                       float bound_mm = std::numeric_limits<float>::infinity());
// The share of a's centreline within D/2 of b's (both poses in one frame): how much of one tube
// the two poses put in the same place. 1 where no centreline was found.
float shared_tube(const LocatorModel& lm, const Pose& a, const Pose& b);

}  // namespace pipeloc
