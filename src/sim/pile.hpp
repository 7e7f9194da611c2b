// A pile of identical pipes dropped one after another into a bin (world frame: origin at the
// centre of the bin floor, Z up). Contact is resolved on a height map of what lies below, so
// no pipe passes into another; each dropped pipe then tilts about horizontal axes while that
// lowers it, so pipes come to rest leaning on one another.
#pragma once

#include <random>
#include <vector>

#include "model/pipe_model.hpp"

namespace pipeloc {

struct BinSpec {
  double inner_x_mm = 640, inner_y_mm = 480;
  double wall_height_mm = 150, wall_thickness_mm = 15;
};

struct PileParams {
  int pipes = 20;
  BinSpec bin;
  double cell_mm = 2.0;        // height-map resolution for contact
  double max_settle_deg = 10;  // largest tilt step tried while settling
  double drop_spread = 0.6;    // pipes are dropped over this share of the bin's width and length
};

// How big a pile of `params.pipes` of this pipe comes out: the pipe's longest extent and
// thickness lying flat, and the pipes' volume (boxes around them) spread evenly over where they
// fall in the bin.
struct PileSize {
  double length_mm = 0, thickness_mm = 0, mean_height_mm = 0;
};
PileSize pile_size(const PipeModel& model, const PileParams& params);

// The bin grown (never shrunk, same proportions) so that the pile fits: the pipe's longest
// extent at most 0.6 x the shorter side (most drops stay inside) and the pile's mean height at
// most 40 mm or 1.5 pipes thick. Returns params.bin when it is large enough already (the
// paper's pipes in piles of 20).
BinSpec bin_for_pile(const PipeModel& model, const PileParams& params);

std::vector<Pose> build_pile(const PipeModel& model, const PileParams& params, std::mt19937& rng);

// The bin as a mesh in the world frame: floor and four walls.
Mesh make_bin_mesh(const BinSpec& bin);

}  // namespace pipeloc
