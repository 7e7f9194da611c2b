// II-B, Algorithm 1: core regions of upward normals, grown while normals stay continuous, kept
// when longer than a * L.
#pragma once

#include <cstdint>
#include <vector>

#include "locate/locate_config.hpp"
#include "locate/normals.hpp"

namespace pipeloc {

struct CandidateRegion {
  int core_begin = 0, core_end = 0;    // cells [begin, end) in RegionBuffers::core_cells
  int cells_begin = 0, cells_end = 0;  // grown region in RegionBuffers::region_cells
  Eigen::Vector3f core_centroid = Eigen::Vector3f::Zero();
  float core_area_mm2 = 0;
  bool short_region = false;  // shorter than a * L: tried after the long ones
};

// Fixed-size working memory, sized once for a Z-buffer and a model.
struct RegionBuffers {
  Image<std::uint8_t> unlabelled_core;  // 1: upward normal, not yet in a core (this frame)
  Image<int> stamp;                     // growth visit marks
  Image<int> reach;                     // growth: steps from the core
  Image<int> claim;                     // cells of regions already taken up: the frame's mark + their core
  int claim_value = 0;
  int stamp_value = 0;
  Image<float> ridge_z;                     // growth: height of the core cell each grown cell came from
  std::vector<int> queue;                   // core labelling: packed column and row of core_cells
  std::vector<int> grow_queue;              // growth: packed column and row of the region's cells
  std::vector<int> core_cells;              // all kept cores' cells
  std::vector<int> region_cells;            // all grown regions' cells
  std::vector<CandidateRegion> candidates;  // capacity max_candidates
  int max_region_cells = 0;
};

struct RegionStats {
  int core_regions = 0;     // connected upward regions before the area test
  int cores_kept = 0;       // after area and extent tests
  int candidates = 0;       // grown regions longer than a * L
  int claimed = 0;          // cores lying mostly in an earlier candidate region: one pipe, grown last
  int retried_claimed = 0;  // candidates of such cores, grown after all the others (retry_claimed_cores)
  int split_cores = 0;      // cores kept from too long ones split along valleys (touching pipes)
  int whole_long_cores = 0;  // cores too long that no valley split, kept whole (pipes end to end)
  int raised_cores = 0;     // cores kept from one too large (the floor) by standing clear above it
  int overlapping = 0;  // grown regions lying mostly in earlier candidate regions: one pipe, not tried again
  int leaked = 0;       // grown over far more than one pipe
  int regrown_after_leak = 0;  // candidates once grown down to the tube's equator only, after a leak
  int not_convex = 0;          // the cells beside the core do not tilt away from it (floor between pipes)
  int short_regions = 0;       // shorter than a * L (and than short_region_min_extent_of_l * L)
  int short_candidates = 0;    // candidates shorter than a * L, tried after the long ones
  int joined = 0;              // long enough once joined to pieces continuing them across gaps
  int leftover = 0;            // candidates of what a pose found in a region left of it (add_leftover_region)
};

void reserve_regions(RegionBuffers* rb, const ZBuffer& zb, const LocateConfig& cfg, float tube_d_mm,
                     float extent_l_mm);

// Algorithm 1's first test, cell by cell: marks in rb->unlabelled_core the cells of rows
// [row_begin, row_end) whose normal is upward. Row bands can be marked on separate threads, as
// soon as their normals are known.
void mark_upward_rows(const ZBuffer& zb, const NormalMap& nm, const LocateConfig& cfg, int row_begin,
                      int row_end, RegionBuffers* rb);

// The share of the cells (Z-buffer indices) under something: with a cell one diameter d away,
// in any of the 8 directions, more than d / 2 higher (another pipe lying across). Candidates are
// tried by core area times the share not under anything, squared.
float share_under_others(const ZBuffer& zb, const int* cells, int n, float d);

// Fills rb->candidates, best first (the largest cores least under other pipes first). Every row
// must have been marked (mark_upward_rows) for this frame's normals. Each candidate is complete
// when on_found(context, candidates so far) is called after it (another thread may work it from
// then on).
using OnCandidateFound = void (*)(void* context, int found);
RegionStats extract_candidate_regions(const ZBuffer& zb, const NormalMap& nm, const LocateConfig& cfg,
                                      float tube_d_mm, float extent_l_mm, RegionBuffers* rb,
                                      OnCandidateFound on_found = nullptr, void* context = nullptr);

// Beyond the paper: one region can hold two pipes (pipes end to end in a core kept whole, a
// neighbour the growth ran onto) and its fit takes at most one. The cells of candidate c's region
// that its pose does not explain (explained[k] zero for its k-th cell): their largest connected
// piece becomes a candidate of its own when it holds upward cells of a core's least area and
// reaches short_region_min_extent_of_l * L. Returns the new candidate's index, or -1 (also when
// max_candidates are taken).
int add_leftover_region(const ZBuffer& zb, const NormalMap& nm, const LocateConfig& cfg, float tube_d_mm,
                        float extent_l_mm, int c, const std::uint8_t* explained, RegionBuffers* rb);

// Longest distance between two of the points (extreme points along 13 directions, then exact
// among those): l_max of Algorithm 1.
float longest_distance(const ZBuffer& zb, const int* cells, int count);

}  // namespace pipeloc
