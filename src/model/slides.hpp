// Beyond the paper: a pipe's slides along itself. An arc turned about its own centre, a coil
// screwed along its helix, a straight run moved along its axis: most of the surface lands on
// itself, and a view that hides the ends fits both poses. These motions are found from the
// model's centreline, so the localizer can judge the slid pose beside the one it found.
#pragma once

#include <vector>

#include "core/pose.hpp"
#include "model/neighbors.hpp"
#include "model/pipe_model.hpp"

namespace pipeloc {

// The tube's centreline as a polyline ordered by arc length from one end, in steps of step_mm:
// each surface sample moved half a diameter inwards along its normal, ordered by the distance
// through the cloud of those points from its farthest end.
struct Centreline {
  std::vector<Eigen::Vector3f> points;
  float step_mm = 0;
  float length_mm() const { return points.size() < 2 ? 0.0f : step_mm * float(points.size() - 1); }
};
Centreline centreline_of(const SurfaceSamples& surface, float tube_d_mm);

// The rigid motion taking the centreline onto itself reversed about one of its points (least
// squares over the part both sides of it share, at least half the line), at the point where that
// fits best: a pipe whose two ends differ (a U or a bend with unequal legs) maps nearly onto
// itself so about the middle of the part they share, which its principal axes miss. Identity
// when the line is too short.
Pose best_reversal(const Centreline& centreline);

// A slide moves the centreline onto itself within this share of D: the slid surface then lies
// within a fraction of a pixel's footprint of the original for any pipe a sensor sees several
// pixels wide, and only the ends tell the two apart. (Arcs and straight runs: under 0.02 D; the
// zoo's coils 0.02-0.04 D; a fat elbow, an S or a long planar bend 0.04-0.08 D; a U or Z over 0.2 D.)
constexpr float kSlideCentrelineRmsOfD = 0.03f;

struct Slide {
  Pose motion;            // model frame to model frame
  float arc_mm = 0;       // how far along the centreline it moves (signed)
  float landing_share = 0;  // of the surface samples within the tolerance of the surface after it
  float centreline_rms_mm = 0;  // of the centreline's overlapping part from itself moved
};

// The surface samples with their k-d tree, built once for the searches below. The samples must
// outlive it.
struct SurfaceIndex {
  explicit SurfaceIndex(const SurfaceSamples& samples) : surface(samples) {
    tree.build(surface.points.data(), surface.points.size());
  }
  const SurfaceSamples& surface;
  KdTree3 tree;
};

// For each arc length s (mm, both signs), the rigid motion taking the centreline onto itself moved
// by s (least squares over the part that overlaps); kept when at least min_share of the surface
// samples land within tolerance_mm of the surface and the centreline lands on itself within 3 % of
// D (model/slides.cpp). None for a part whose shape changes along it.
std::vector<Slide> find_slides(const SurfaceIndex& surface, const Centreline& centreline, float tube_d_mm,
                               const std::vector<float>& arc_mm, float tolerance_mm, float min_share);

// The share of the surface samples that land within tolerance_mm of the surface after motion m.
float share_landing_on_itself(const SurfaceIndex& surface, const Pose& m, float tolerance_mm);

}  // namespace pipeloc
