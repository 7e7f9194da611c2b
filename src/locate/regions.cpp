#include "locate/regions.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace pipeloc {
namespace {

constexpr double kDeg = M_PI / 180.0;
// Joining pieces of a top strip: at most this many joins per region, and the direction of each
// piece's end within this angle of the gap (a bend turns the strip a little across it).
constexpr int kMaxJoins = 4;
constexpr double kJoinMaxTurnDeg = 35;
constexpr float kJoinMaxSlope = 0.3f;  // height change per mm of gap (a pipe leaning on others)
// A region that leaks is grown again down to this share of D below its core: the tube's equator.
constexpr float kLeakedDropOfD = 0.5f;
struct JoinEnd {
  int core, end;
};
// The top of a pipe resting on a surface stands at least about 0.85 D above it (where its normal
// is within 45 degrees of up): cells more than max(0.5 D, 3 sigma) above the plane a core too
// large to be pipes lies in are taken for pipes' tops.
constexpr float kTopRiseOfD = 0.5f;
constexpr float kTopRiseOfSigma = 3.0f;
// A core cell lies under something when a cell one diameter away, in any of the 8 directions,
// is more than this share of D higher: another pipe across it (share_under_others() looks at
// kCoveredSamples cells at most).
constexpr float kCoveringRiseOfD = 0.5f;
constexpr int kCoveredSamples = 200;
const int kDi[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
const int kDj[8] = {-1, -1, -1, 0, 0, 1, 1, 1};

// A cell is upward (II-B's N . Nv > cos N_th1) where its normal's z exceeds this.
float upward_min_z(const LocateConfig& cfg) { return float(std::cos(cfg.upward_normal_max_deg * kDeg)); }
// The least extent of a region tried at all: short ones down to short_region_min_extent_of_l * L.
float short_min_extent_mm(const LocateConfig& cfg, float l) {
  return float(std::min(cfg.short_region_min_extent_of_l, cfg.region_min_extent_of_l)) * l;
}

// Breadth-first queues keep each cell's column and row packed in one int beside its buffer
// index: no division per visited cell.
int pack(int i, int j) { return (j << 16) | i; }
int column_of(int packed) { return packed & 0xffff; }
int row_of(int packed) { return packed >> 16; }

// The first of `span` mark values not yet used in `marks`. A deployed cell runs for weeks: when
// the values would run out, the marks are cleared and counting starts again.
int fresh_marks(Image<int>* marks, int* used, int span) {
  if (*used > std::numeric_limits<int>::max() - span) {
    std::fill(marks->pixels.begin(), marks->pixels.end(), 0);
    *used = 0;
  }
  const int first = *used + 1;
  *used += span;
  return first;
}

// The bounding box of a set of cells bounds its l_max (as longest_distance measures it, with
// the coordinate axes among its directions) from below by its longest side and from above by its
// diagonal: most sets are decided by that alone.
struct CellBox {
  int i0 = 1 << 30, i1 = -1, j0 = 1 << 30, j1 = -1;
  float z0 = 1e30f, z1 = -1e30f;
  void add(int i, int j, float z) {
    i0 = std::min(i0, i), i1 = std::max(i1, i), j0 = std::min(j0, j), j1 = std::max(j1, j);
    z0 = std::min(z0, z), z1 = std::max(z1, z);
  }
  // l_max > limit_mm, from the box when it decides, else measured.
  bool longer_than(float limit_mm, const ZBuffer& zb, const int* cells, int count) const {
    constexpr float kRounding = 0.01f;  // the box is in cell units, longest_distance in bin coordinates
    const float dx = float((i1 - i0) * zb.pixel_mm), dy = float((j1 - j0) * zb.pixel_mm), dz = z1 - z0;
    if (std::max({dx, dy, dz}) > limit_mm + kRounding) return true;
    if (std::sqrt(dx * dx + dy * dy + dz * dz) < limit_mm - kRounding) return false;
    return longest_distance(zb, cells, count) > limit_mm;
  }
};

}  // namespace

void reserve_regions(RegionBuffers* rb, const ZBuffer& zb, const LocateConfig& cfg, float d, float l) {
  const std::size_t cells = zb.z.pixels.size();
  rb->unlabelled_core.resize(zb.z.width, zb.z.height, 0);
  rb->stamp.resize(zb.z.width, zb.z.height, 0);
  rb->reach.resize(zb.z.width, zb.z.height, 0);
  rb->claim.resize(zb.z.width, zb.z.height, 0);
  rb->ridge_z.resize(zb.z.width, zb.z.height, 0.0f);
  rb->queue.assign(cells, 0);
  rb->core_cells.assign(cells, 0);
  // A pipe's visible region is at most about L x D; allow three times that before calling it a leak.
  rb->max_region_cells = int(3.0 * (l + d) * d / (zb.pixel_mm * zb.pixel_mm));
  rb->region_cells.assign(std::size_t(rb->max_region_cells) * cfg.max_candidates, 0);
  rb->grow_queue.assign(std::size_t(rb->max_region_cells), 0);
  rb->candidates.reserve(cfg.max_candidates);
}

float longest_distance(const ZBuffer& zb, const int* cells, int count) {
  static const float dirs[13][3] = {{1, 0, 0},  {0, 1, 0},  {0, 0, 1}, {1, 1, 0},  {1, -1, 0},
                                    {1, 0, 1},  {1, 0, -1}, {0, 1, 1}, {0, 1, -1}, {1, 1, 1},
                                    {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}};
  int extreme[26];
  float best[26];
  for (int d = 0; d < 26; ++d) best[d] = -1e30f, extreme[d] = cells[0];
  const int w = zb.z.width;
  for (int c = 0; c < count; ++c) {
    const Eigen::Vector3f p = zb.point(cells[c] % w, cells[c] / w);
    for (int d = 0; d < 13; ++d) {
      const float s = p.x() * dirs[d][0] + p.y() * dirs[d][1] + p.z() * dirs[d][2];
      if (s > best[2 * d]) best[2 * d] = s, extreme[2 * d] = cells[c];
      if (-s > best[2 * d + 1]) best[2 * d + 1] = -s, extreme[2 * d + 1] = cells[c];
    }
  }
  float longest = 0;
  for (int a = 0; a < 26; ++a)
    for (int b = a + 1; b < 26; ++b)
      longest = std::max(
          longest,
          (zb.point(extreme[a] % w, extreme[a] / w) - zb.point(extreme[b] % w, extreme[b] / w)).norm());
  return longest;
}

int add_leftover_region(const ZBuffer& zb, const NormalMap& nm, const LocateConfig& cfg, float d, float l,
                        int c, const std::uint8_t* explained, RegionBuffers* rb) {
  const int slot = int(rb->candidates.size());
  if (slot >= cfg.max_candidates) return -1;
  const CandidateRegion& from = rb->candidates[std::size_t(c)];
  const int* cells = &rb->region_cells[std::size_t(from.cells_begin)];
  const int n = from.cells_end - from.cells_begin;
  const float cell_area = float(zb.pixel_mm * zb.pixel_mm);
  const float area_min = float(cfg.core_min_area_of_d2) * d * d;
  const float up_min = upward_min_z(cfg);
  const auto upward = [&](int cell) { return nm.n.pixels[std::size_t(cell)].z() > up_min; };
  int open_up = 0;
  for (int k = 0; k < n; ++k) open_up += !explained[k] && upward(cells[k]);
  if (float(open_up) * cell_area < area_min) return -1;
  // The cells left are marked `left`; each piece, labelled into grow_queue, is marked `left + 1`.
  const int left = fresh_marks(&rb->stamp, &rb->stamp_value, 2);
  for (int k = 0; k < n; ++k)
    if (!explained[k]) rb->stamp.pixels[std::size_t(cells[k])] = left;
  const int w = zb.z.width;
  int* out = &rb->region_cells[std::size_t(slot) * std::size_t(rb->max_region_cells)];
  int best = 0;
  for (int k = 0; k < n; ++k) {
    if (rb->stamp.pixels[std::size_t(cells[k])] != left) continue;
    int count = 0;
    rb->grow_queue[count++] = pack(cells[k] % w, cells[k] / w);
    rb->stamp.pixels[std::size_t(cells[k])] = left + 1;
    for (int head = 0; head < count; ++head) {
      const int ci = column_of(rb->grow_queue[head]), cj = row_of(rb->grow_queue[head]);
      for (int q = 0; q < 8; ++q) {
        const int ni = ci + kDi[q], nj = cj + kDj[q];
        if (ni < 0 || nj < 0 || ni >= zb.width || nj >= zb.height) continue;
        int& mark = rb->stamp.at(ni, nj);
        if (mark != left) continue;
        mark = left + 1;
        rb->grow_queue[count++] = pack(ni, nj);
      }
    }
    if (count <= best) continue;
    best = count;
    for (int q = 0; q < count; ++q) out[q] = row_of(rb->grow_queue[q]) * w + column_of(rb->grow_queue[q]);
  }
  // Like a core: upward cells of at least A_th, whose centroid places the axis (III).
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  int up = 0;
  for (int q = 0; q < best; ++q)
    if (upward(out[q])) centroid += zb.point(out[q] % w, out[q] / w), ++up;
  if (float(up) * cell_area < area_min) return -1;
  const float extent = longest_distance(zb, out, best);
  if (extent < short_min_extent_mm(cfg, l)) return -1;
  CandidateRegion r;
  r.core_begin = r.core_end = 0;  // no core of its own
  r.cells_begin = slot * rb->max_region_cells;
  r.cells_end = r.cells_begin + best;
  r.core_centroid = centroid / float(up);
  r.core_area_mm2 = float(up) * cell_area;
  r.short_region = extent < float(cfg.region_min_extent_of_l) * l;
  rb->candidates.push_back(r);
  return slot;
}

float share_under_others(const ZBuffer& zb, const int* cells, int n, float d) {
  const int reach = std::max(1, int(std::lround(d / zb.pixel_mm)));
  const float rise = kCoveringRiseOfD * d;
  const int w = zb.z.width;
  int looked = 0, under = 0;
  for (int k = 0; k < n; k += std::max(1, n / kCoveredSamples)) {
    const int i = cells[k] % w, j = cells[k] / w;
    const float above = zb.z.at(i, j) + rise;
    bool covered = false;
    for (int q = 0; q < 8 && !covered; ++q) {
      const int ni = i + kDi[q] * reach, nj = j + kDj[q] * reach;
      covered = zb.valid(ni, nj) && zb.z.at(ni, nj) > above;
    }
    ++looked, under += covered;
  }
  return looked ? float(under) / float(looked) : 0.0f;
}

void mark_upward_rows(const ZBuffer& zb, const NormalMap& nm, const LocateConfig& cfg, int row_begin,
                      int row_end, RegionBuffers* rb) {
  const float up_min = upward_min_z(cfg);
  Image<std::uint8_t>& open = rb->unlabelled_core;
  for (int j = row_begin; j < row_end; ++j)
    for (int i = 0; i < zb.width; ++i) open.at(i, j) = nm.n.at(i, j).z() > up_min;
}

RegionStats extract_candidate_regions(const ZBuffer& zb, const NormalMap& nm, const LocateConfig& cfg,
                                      float d, float l, RegionBuffers* rb, OnCandidateFound on_found,
                                      void* context) {
  RegionStats stats;
  rb->candidates.clear();
  const int w = zb.z.width;
  const float cont_min = float(std::cos(cfg.continuity_max_deg * kDeg));
  const float step_max = float(cfg.continuity_step_max_mm);
  const float drop_max = float(cfg.region_max_drop_of_d) * d;
  const int reach_max = std::max(1, int(cfg.region_max_reach_of_d * d / zb.pixel_mm));
  const float cell_area = float(zb.pixel_mm * zb.pixel_mm);
  const float area_min = float(cfg.core_min_area_of_d2) * d * d;
  const float core_extent_max = float(cfg.core_max_extent_of_l) * l;
  const float whole_extent_max = float(cfg.core_whole_max_extent_of_l) * l;
  const float up_min = upward_min_z(cfg);
  const int bridge_cells = int(cfg.hole_bridge_of_d * d / zb.pixel_mm);

  // Upward cells were marked once (mark_upward_rows); labelling reads one byte per neighbour.
  Image<std::uint8_t>& open = rb->unlabelled_core;

  // 1. Connected regions (8-connectivity) of upward normals with A_n >= A_th.
  struct Core {
    int begin, end;
    float area;
    bool split;           // a piece of a core too long, split along valleys
    float rank_area = 0;  // area x (share of its cells not under another pipe)^2: the order tried
  };
  int pool = 0;
  // Cores are kept in the pool in discovery order; their list is small and lives on the stack.
  constexpr int kMaxCores = 256;
  Core cores[kMaxCores];
  int n_cores = 0;
  // Offsets of the 8 neighbours in the buffers' pixels (the label image has the Z-buffer's width).
  int neighbour[8];
  for (int k = 0; k < 8; ++k) neighbour[k] = kDj[k] * w + kDi[k];
  // The cells marked `mark` connected to (i, j), appended to the pool (and unmarked).
  const auto label = [&](int i, int j, std::uint8_t mark) {
    const int begin = pool;
    CellBox box;
    open.at(i, j) = 0;
    rb->queue[pool] = pack(i, j);
    rb->core_cells[pool++] = zb.index(i, j);
    for (int head = begin; head < pool; ++head) {
      const int ci = column_of(rb->queue[head]), cj = row_of(rb->queue[head]);
      const int at = rb->core_cells[head];
      box.add(ci, cj, zb.z.pixels[std::size_t(at)]);
      // Away from the edges every neighbour exists: no bounds tests.
      const bool inside = ci > 0 && cj > 0 && ci + 1 < zb.width && cj + 1 < zb.height;
      for (int k = 0; k < 8; ++k) {
        const int ni = ci + kDi[k], nj = cj + kDj[k];
        if (!inside && (ni < 0 || nj < 0 || ni >= zb.width || nj >= zb.height)) continue;
        const int q = at + neighbour[k];
        if (open.pixels[std::size_t(q)] != mark) continue;
        open.pixels[std::size_t(q)] = 0;
        rb->queue[pool] = pack(ni, nj);
        rb->core_cells[pool++] = q;
      }
    }
    return box;
  };
  // A core of A_n >= A_th no longer than core_max_extent_of_l * L is kept.
  const auto keep_core = [&](int begin, const CellBox& box) {
    const float area = float(pool - begin) * cell_area;
    if (area < area_min || n_cores >= kMaxCores ||
        box.longer_than(core_extent_max, zb, &rb->core_cells[begin], pool - begin))
      return false;
    cores[n_cores++] = {begin, pool, area, false};
    return true;
  };
  // Beyond the paper: where two pipes lie side by side touching, plane fits straddling the V
  // between them give upward normals, and the two tops become one core, too long to be one pipe.
  // Across a valley the normals turn towards each other (across a tube's top they turn apart);
  // compared a quarter diameter either side, such cells are taken out of a core too long, and
  // what falls apart is labelled again.
  const int side = std::max(1, int(std::lround(0.25 * d / zb.pixel_mm)));
  const float valley_turn = float(cfg.core_valley_turn);
  const float split_area_max = float(cfg.core_split_max_area_of_ld) * l * d;
  const auto in_valley = [&](int i, int j) {
    if (i < side || j < side || i + side >= zb.width || j + side >= zb.height) return false;
    const Eigen::Vector3f &l = nm.n.at(i - side, j), &r = nm.n.at(i + side, j);
    const Eigen::Vector3f &b = nm.n.at(i, j - side), &t = nm.n.at(i, j + side);
    return (has_normal(l) && has_normal(r) && l.x() - r.x() > valley_turn) ||
           (has_normal(b) && has_normal(t) && b.y() - t.y() > valley_turn);
  };
  // Beyond the paper: a core far larger than pipes side by side can be is the floor (or a flat
  // surface under the pipes), and a thin pipe lying on it joins it where noise turned a normal on
  // the pipe's side upward. The pipe's top stands clear above the plane the core lies in: the
  // floor's own cells lie in it within the noise, the top of a pipe resting on it about D above.
  const float rise_min = std::max(kTopRiseOfD * d, kTopRiseOfSigma * float(cfg.frame_sigma_mm));
  // The plane z = a i + b j + c the cells of pool[begin, end) lie in (least squares, cell units
  // about the core's first cell: no cancellation).
  const auto fitted_plane = [&](int begin, int end) {
    const int i0 = column_of(rb->queue[begin]), j0 = row_of(rb->queue[begin]);
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (int k = begin; k < end; ++k) {
      const Eigen::Vector3d u(column_of(rb->queue[k]) - i0, row_of(rb->queue[k]) - j0, 1.0);
      a += u * u.transpose(), b += u * double(zb.z.pixels[std::size_t(rb->core_cells[k])]);
    }
    const Eigen::Vector3d abc = a.ldlt().solve(b);
    return [abc, i0, j0](int i, int j) { return float(abc[0] * (i - i0) + abc[1] * (j - j0) + abc[2]); };
  };
  constexpr std::uint8_t kOpen = 1, kSplit = 2;
  const int pool_capacity = int(rb->core_cells.size());
  // The cells of the dropped core pool[begin, end) for which `piece_cell` holds, labelled again
  // into the pool after it (none when there is no room for them all): the pieces that pass as
  // cores are kept where the whole core was. Returns how many.
  const auto split_core = [&](int begin, int end, const auto& piece_cell) {
    int marked_cells = 0;
    for (int k = begin; k < end; ++k) {
      const int ci = column_of(rb->queue[k]), cj = row_of(rb->queue[k]);
      if (piece_cell(ci, cj)) open.at(ci, cj) = kSplit, ++marked_cells;
    }
    if (end + marked_cells > pool_capacity) {
      for (int k = begin; k < end; ++k) open.pixels[std::size_t(rb->core_cells[k])] = 0;
      return 0;
    }
    // The pieces are labelled after the whole core, which is read to its end for their seeds.
    pool = end;
    const int first_piece = n_cores;
    for (int k = begin; k < end; ++k) {
      const int ci = column_of(rb->queue[k]), cj = row_of(rb->queue[k]);
      if (open.at(ci, cj) != kSplit) continue;
      const int piece = pool;
      if (!keep_core(piece, label(ci, cj, kSplit))) pool = piece;
    }
    // Then the pieces kept move down to where the whole core was (no overlap: they hold a
    // subset of its cells and lie after it).
    int write = begin;
    for (int c = first_piece; c < n_cores; ++c) {
      Core& kept = cores[c];
      std::copy(&rb->queue[kept.begin], &rb->queue[kept.end], &rb->queue[write]);
      std::copy(&rb->core_cells[kept.begin], &rb->core_cells[kept.end], &rb->core_cells[write]);
      kept.end = write + (kept.end - kept.begin), kept.begin = write, kept.split = true;
      write = kept.end;
    }
    pool = write;
    return n_cores - first_piece;
  };
  for (int j = 0; j < zb.height; ++j) {
    for (int i = 0; i < zb.width; ++i) {
      if (open.at(i, j) != kOpen) continue;
      ++stats.core_regions;
      const int begin = pool;
      const CellBox box = label(i, j, kOpen);
      if (keep_core(begin, box)) continue;
      const int end = pool;
      pool = begin;  // seen, dropped ...
      const float core_area = float(end - begin) * cell_area;
      if (core_area < area_min) continue;
      if (core_area > split_area_max) {
        // ... unless, the floor, it has pipes' tops standing on it.
        const auto plane = fitted_plane(begin, end);
        stats.raised_cores += split_core(begin, end, [&](int ci, int cj) {
          return zb.z.at(ci, cj) - plane(ci, cj) > rise_min && !(valley_turn > 0 && in_valley(ci, cj));
        });
        continue;
      }
      // ... unless, too long, it falls apart along valleys into pieces that are cores ...
      const int pieces =
          valley_turn > 0 ? split_core(begin, end, [&](int ci, int cj) { return !in_valley(ci, cj); }) : 0;
      stats.split_cores += pieces;
      // ... or, beyond the paper, no longer than core_whole_max_extent_of_l * L, it is kept whole:
      // pipes lying end to end, touching at the same height, show one top strip and no valley
      // between them; the ridge fit takes one pipe out of it (09-S-sym of the zoo: 19 of 66
      // pipes missed had no core of their own). A failed split left the pool and the core's
      // cells as they were.
      if (pieces == 0 && n_cores < kMaxCores && whole_extent_max > 0 &&
          !box.longer_than(whole_extent_max, zb, &rb->core_cells[begin], end - begin)) {
        pool = end;
        cores[n_cores++] = {begin, end, core_area, false};
        ++stats.whole_long_cores;
      }
    }
  }
  stats.cores_kept = n_cores;
  // Most promising first: the largest cores are the least covered pipes, but a pipe lying under
  // another shows a large core too, beside the pipe across it (50 coils of the zoo: 42 of the 144
  // candidates tried lay on top). Its cells under something count against it.
  for (int c = 0; c < n_cores; ++c) {
    Core& core = cores[c];
    const float open_share =
        1.0f - share_under_others(zb, &rb->core_cells[core.begin], core.end - core.begin, d);
    core.rank_area = core.area * open_share * open_share;
  }
  // Equal ranks in raster order of their first cell: the order does not depend on where the pool holds them.
  std::sort(cores, cores + n_cores, [&](const Core& a, const Core& b) {
    return a.rank_area != b.rank_area ? a.rank_area > b.rank_area
                                      : rb->core_cells[a.begin] < rb->core_cells[b.begin];
  });

  // Beyond the paper: joining pieces of a top strip. The two ends of a core (bin frame: its
  // farthest cells) and the direction it runs out at each, computed when first asked for.
  const float join_gap = float(cfg.region_join_gap_of_d) * d;
  const float join_height_tol = std::max(0.25f * d, 3.0f * float(cfg.frame_sigma_mm));
  const float join_cos = float(std::cos(kJoinMaxTurnDeg * kDeg));
  struct Ends {
    bool known = false;
    Eigen::Vector3f p[2], dir[2];
  };
  Ends ends[kMaxCores];
  const auto core_point = [&](int k) { return zb.point(column_of(rb->queue[k]), row_of(rb->queue[k])); };
  const auto ends_of = [&](int c) -> const Ends& {
    Ends& e = ends[c];
    if (e.known) return e;
    const int b = cores[c].begin, n = cores[c].end - cores[c].begin;
    const auto farthest = [&](const Eigen::Vector3f& from) {
      int far = b;
      float best = -1;
      for (int k = b; k < b + n; ++k)
        if (const float d2 = (core_point(k) - from).squaredNorm(); d2 > best) best = d2, far = k;
      return core_point(far);
    };
    e.p[0] = farthest(core_point(b));
    e.p[1] = farthest(e.p[0]);
    // Along the strip at each end: the principal direction (in plan) of its cells within 2 D of
    // the end, turned to point out of the core.
    const float r2 = (2.0f * d) * (2.0f * d);
    for (int s = 0; s < 2; ++s) {
      Eigen::Vector2f sum = Eigen::Vector2f::Zero();
      Eigen::Matrix2f sum_sq = Eigen::Matrix2f::Zero();
      int m = 0;
      for (int k = b; k < b + n; ++k)
        if (const Eigen::Vector3f q = core_point(k); (q - e.p[s]).squaredNorm() <= r2) {
          const Eigen::Vector2f v = q.head<2>() - e.p[s].head<2>();  // about the end: no cancellation
          sum += v, sum_sq += v * v.transpose(), ++m;
        }
      const Eigen::Vector2f mean = sum / float(std::max(1, m));
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2f> eig(sum_sq / float(std::max(1, m)) -
                                                               mean * mean.transpose());
      Eigen::Vector2f along = eig.eigenvectors().col(1);
      if (along.dot(-mean) < 0) along = -along;  // the mean lies inside the core from the end
      e.dir[s] = Eigen::Vector3f(along.x(), along.y(), 0);
    }
    e.known = true;
    return e;
  };
  // Nothing on the straight gap between two ends lies lower than the line joining them (the pipe
  // would be seen there): the cells are empty, the pipe's own top, or something lying across it.
  const auto gap_covered = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    const int steps = int((b - a).head<2>().norm() / float(zb.pixel_mm)) + 1;
    for (int s = 1; s < steps; ++s) {
      const Eigen::Vector3f q = a + (b - a) * (float(s) / float(steps));
      const int i = int(round_nearest(float((q.x() - zb.origin_x_mm) / zb.pixel_mm)));
      const int j = int(round_nearest(float((q.y() - zb.origin_y_mm) / zb.pixel_mm)));
      if (zb.valid(i, j) && zb.z.at(i, j) < q.z() - join_height_tol) return false;
    }
    return true;
  };
  // A candidate region's cells are marked claim + the index of the core it grew from: a core
  // yields only to the regions of cores before it (larger ones). A short region, grown again
  // after the long ones, is not lost to a long region of a smaller core that ran over its pipe.
  const int claim = fresh_marks(&rb->claim, &rb->claim_value, kMaxCores);
  // How many of the cells carry a mark in [first, end); whether most of core c's do.
  const auto marked = [&](const Image<int>& marks, int first, int end, const int* cells, int n) {
    int in = 0;
    for (int k = 0; k < n; ++k) {
      const int m = marks.pixels[std::size_t(cells[k])];
      in += m >= first && m < end;
    }
    return in;
  };
  const auto core_mostly_marked = [&](const Image<int>& marks, int first, int end, int c) {
    const int n = cores[c].end - cores[c].begin;
    return 2 * marked(marks, first, end, &rb->core_cells[std::size_t(cores[c].begin)], n) > n;
  };
  // The core continuing one of the region's open ends across a gap, nearest first; that end is
  // then replaced by the partner's far end. {-1, 0} when none.
  const auto join_partner = [&](JoinEnd open_ends[2], int stamp, int claimed_before) -> JoinEnd {
    JoinEnd best{-1, 0};
    int best_end = -1;
    float best_gap = join_gap;
    for (int e = 0; e < 2; ++e) {
      const Ends& a = ends_of(open_ends[e].core);
      const Eigen::Vector3f pa = a.p[open_ends[e].end], ua = a.dir[open_ends[e].end];
      for (int k = 0; k < n_cores; ++k) {
        const Ends& b = ends_of(k);
        for (int f = 0; f < 2; ++f) {
          const Eigen::Vector3f g = b.p[f] - pa;
          const float gap = g.head<2>().norm();
          if (gap >= best_gap || gap <= 0) continue;
          const Eigen::Vector3f u(g.x() / gap, g.y() / gap, 0);
          if (ua.dot(u) < join_cos || -b.dir[f].dot(u) < join_cos) continue;
          if (std::abs(g.z()) > join_height_tol + kJoinMaxSlope * gap) continue;
          if (core_mostly_marked(rb->stamp, stamp, stamp + 1, k) ||
              core_mostly_marked(rb->claim, claim, claimed_before, k))
            continue;
          if (!gap_covered(pa, b.p[f])) continue;
          best = {k, f}, best_end = e, best_gap = gap;
        }
      }
    }
    if (best.core >= 0) open_ends[best_end] = {best.core, 1 - best.end};
    return best;
  };

  // 2. Grow each core while the normal of a neighbour is close to that of the boundary cell.
  // grow_core(c, min_extent, drop) grows core c into a region, at most drop below the core's
  // cells it grew from, a candidate when it is longer than min_extent, and says what became of it.
  enum class Grown { candidate, claimed, overlapping, leaked, not_convex, too_short };
  int region_pool = 0;
  const float long_extent = float(cfg.region_min_extent_of_l) * l;
  // Beyond the paper: a core lying mostly in an earlier candidate's region is most often another
  // piece of that pipe's top, but in a pile it may be a touching neighbour's region grown over it:
  // with retry_claimed_cores such cores are grown again after all the others, while there is room,
  // without either claim test (a second region of one pipe is merged into the first when located).
  bool retrying_claimed = false;
  const auto grow_core = [&](int c, float min_extent, float drop) {
    // A core lying mostly in the region of a larger one is another piece of that pipe's top.
    const int core_count = cores[c].end - cores[c].begin;
    if (!retrying_claimed && core_mostly_marked(rb->claim, claim, claim + c, c)) return Grown::claimed;
    // Growth is first held to region_max_reach_of_d * D from the core: a pipe's visible surface
    // lies within about D/2 of its top strip, and a touching pipe then adds a band, not itself.
    // A region too short that way (a top strip broken into pieces) is grown on without the
    // limit, the paper's growth, and kept if it then neither leaks nor stays short.
    int* cells = &rb->region_cells[region_pool];
    int count = 0;
    const int stamp = fresh_marks(&rb->stamp, &rb->stamp_value, 1);
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
    CellBox box;
    for (int k = cores[c].begin; k < cores[c].end && count < rb->max_region_cells; ++k) {
      rb->grow_queue[count] = rb->queue[k];
      cells[count++] = rb->core_cells[k];
      rb->stamp.pixels[rb->core_cells[k]] = stamp;
      rb->ridge_z.pixels[rb->core_cells[k]] = zb.z.pixels[rb->core_cells[k]];
      rb->reach.pixels[rb->core_cells[k]] = 0;
      centroid += zb.point(rb->core_cells[k] % w, rb->core_cells[k] / w);
    }
    centroid /= float(core_count);
    bool leaked = false;
    int ring_cells = 0, ring_lower = 0;
    // A pipe's top is convex: the cells grown straight from its core tilt away from it. A patch of
    // floor between pipes grows up their sides instead. Known once the core's cells are worked.
    const auto convex = [&] {
      return ring_cells > 0 && float(ring_lower) >= float(cfg.convexity_min_share) * float(ring_cells);
    };
    const bool split = cores[c].split;
    // The queue is breadth-first, in order of reach: the cells the first pass did not grow from
    // are its last ones. Growing on from the first of them is the unlimited growth from scratch.
    int held_back = -1;
    // Grows breadth-first from queue position `from` on; cells beyond reach_limit are held back.
    const auto grow = [&](int from, int reach_limit) {
      for (int head = from; head < count; ++head) {
        const int ci = column_of(rb->grow_queue[head]), cj = row_of(rb->grow_queue[head]);
        const int at = cells[head];
        const Eigen::Vector3f ni_n = nm.n.pixels[std::size_t(at)];
        const float zi = zb.z.pixels[std::size_t(at)];
        box.add(ci, cj, zi);
        const int reach = rb->reach.pixels[std::size_t(at)] + 1;
        if (reach > reach_limit) {
          if (held_back < 0) held_back = head;
          continue;
        }
        // The visible part of a pipe lies within about one diameter below its top: growth does
        // not follow a smoothed edge down onto the floor or the pipe beneath.
        const float top = rb->ridge_z.pixels[std::size_t(at)];
        const bool inside = ci > 0 && cj > 0 && ci + 1 < zb.width && cj + 1 < zb.height;
        for (int k = 0; k < 8; ++k) {
          const int ni = ci + kDi[k], nj = cj + kDj[k];
          if (!inside && (ni < 0 || nj < 0 || ni >= zb.width || nj >= zb.height)) continue;
          std::size_t q = std::size_t(at + neighbour[k]);
          int gap = 0;  // empty cells crossed to reach q
          // Beyond the paper: a hole in the top strip (a glint, a dropout) longer than the hole
          // filling splits the strip into pieces each too short for a * L. With hole_bridge_of_d
          // set, growth steps from an upward cell across empty cells (no reading) to the next
          // upward cell within bridge_cells, at the height the slope predicts: one pipe, not two
          // pieces. Off by default: it costs the dev set's torus two pipes (docs/experiments.md).
          if (std::isnan(zb.z.pixels[q]) && bridge_cells > 0 && ni_n.z() > up_min) {
            int gi = ni, gj = nj;
            const auto in_bounds = [&](int i, int j) {
              return i >= 0 && j >= 0 && i < zb.width && j < zb.height;
            };
            while (gap < bridge_cells && in_bounds(gi, gj) && !zb.valid(gi, gj))
              gi += kDi[k], gj += kDj[k], ++gap;
            if (!zb.valid(gi, gj)) continue;
            q = std::size_t(zb.index(gi, gj));
            if (!(nm.n.pixels[q].z() > up_min)) continue;
            const float dz_per_cell =
                -(ni_n.x() * float(kDi[k]) + ni_n.y() * float(kDj[k])) / ni_n.z() * float(zb.pixel_mm);
            if (std::abs(zb.z.pixels[q] - (zi + dz_per_cell * float(gap + 1))) > step_max) continue;
          }
          int& s = rb->stamp.pixels[q];
          if (s == stamp) continue;
          const Eigen::Vector3f& nn = nm.n.pixels[q];
          if (!has_normal(nn)) continue;
          const float zq = zb.z.pixels[q];
          if (nn.dot(ni_n) <= cont_min || (gap == 0 && std::abs(zq - zi) > step_max) || zq < top - drop)
            continue;
          // A piece of a split core does not grow back over the valley it was split along.
          if (split && in_valley(ni, nj)) continue;
          rb->ridge_z.pixels[q] = top;
          rb->reach.pixels[q] = reach + gap;
          if (count >= rb->max_region_cells) {
            leaked = true;
            break;
          }
          s = stamp;
          rb->grow_queue[count] = pack(int(q) % w, int(q) / w);
          cells[count++] = int(q);
          // Convex: beside the core the surface tilts away from it (plane-fit normals, not noisy heights).
          if (head < core_count)
            ++ring_cells, ring_lower += nn.x() * float(kDi[k]) + nn.y() * float(kDj[k]) > 0;
        }
        if (leaked || (head + 1 == core_count && !convex())) return;
      }
    };
    grow(0, reach_max);
    bool found = !leaked && convex() && box.longer_than(min_extent, zb, cells, count);
    // Beyond the paper: a top strip cut by a pipe lying across it, or by a dropout, falls into
    // pieces each too short. The piece continuing this one across the gap (same direction, same
    // height, nothing lower between) is grown with it: one pipe.
    if (!found && !leaked && convex() && join_gap > 0) {
      JoinEnd open_ends[2] = {{c, 0}, {c, 1}};  // the joined strip's two ends
      for (int joins = 0; joins < kMaxJoins && !found; ++joins) {
        const JoinEnd next = join_partner(open_ends, stamp, claim + c);
        if (next.core < 0) break;
        const int from = count;
        for (int k = cores[next.core].begin; k < cores[next.core].end && count < rb->max_region_cells; ++k) {
          const int q = rb->core_cells[k];
          if (rb->stamp.pixels[q] == stamp) continue;
          rb->stamp.pixels[q] = stamp;
          rb->grow_queue[count] = rb->queue[k];
          cells[count++] = q;
          rb->ridge_z.pixels[q] = zb.z.pixels[q];
          rb->reach.pixels[q] = 0;
        }
        grow(from, reach_max);
        if (leaked) break;
        found = box.longer_than(min_extent, zb, cells, count);
        if (found) ++stats.joined;
      }
    }
    // Growth held to reach_max that held nothing back is all growth there is; otherwise a region
    // still too short is grown on without the limit (the paper's growth) from where it stopped.
    if (!found && !leaked && convex() && held_back >= 0) {
      grow(held_back, std::numeric_limits<int>::max() - 1);
      found = !leaked && box.longer_than(min_extent, zb, cells, count);
    }
    if (!found) return leaked ? Grown::leaked : !convex() ? Grown::not_convex : Grown::too_short;
    // A region lying mostly in earlier ones is another piece of a pipe already taken up (a top
    // strip broken into pieces whose cores lay apart).
    if (!retrying_claimed && float(marked(rb->claim, claim, claim + c, cells, count)) >
                                 float(cfg.region_max_claimed_share) * float(count))
      return Grown::overlapping;
    CandidateRegion r;
    r.core_begin = cores[c].begin;
    r.core_end = cores[c].end;
    r.cells_begin = region_pool;
    r.cells_end = region_pool + count;
    r.core_centroid = centroid;
    r.core_area_mm2 = cores[c].area;
    r.short_region = min_extent < long_extent;
    rb->candidates.push_back(r);
    for (int k = 0; k < count; ++k) rb->claim.pixels[cells[k]] = claim + c;
    region_pool += rb->max_region_cells;
    if (on_found) on_found(context, int(rb->candidates.size()));
    return Grown::candidate;
  };
  const auto count_outcome = [&](Grown g) {
    if (g == Grown::claimed) ++stats.claimed;
    if (g == Grown::overlapping) ++stats.overlapping;
    if (g == Grown::leaked) ++stats.leaked;
    if (g == Grown::not_convex) ++stats.not_convex;
    if (g == Grown::too_short) ++stats.short_regions;
  };
  const auto room = [&] { return int(rb->candidates.size()) < cfg.max_candidates; };
  // Beyond the paper: a region shorter than a * L is not dropped but tried after all the long
  // ones (a top strip broken into pieces the joins did not mend, a pipe partly out of view), when
  // it reaches short_region_min_extent_of_l * L: its fit and the verification judge it, and it
  // cannot take a long region's place among the max_candidates.
  const float short_min_extent = short_min_extent_mm(cfg, l);
  struct Deferred {
    int core;
    float drop;  // grown with
  };
  Deferred short_cores[kMaxCores];
  int n_short = 0;
  int claimed_cores[kMaxCores];
  int n_claimed = 0;
  // A region too short waits for the short pass below, with the drop it was grown with; a core
  // claimed, for the last pass.
  const auto settle = [&](int c, float drop, Grown g) {
    if (g == Grown::claimed && cfg.retry_claimed_cores) claimed_cores[n_claimed++] = c;
    if (g == Grown::too_short && short_min_extent < long_extent)
      short_cores[n_short++] = {c, drop};
    else
      count_outcome(g);
  };
  int leaked_cores[kMaxCores];
  int n_leaked = 0;
  for (int c = 0; c < n_cores && room(); ++c) {
    const Grown g = grow_core(c, long_extent, drop_max);
    if (g == Grown::leaked)
      leaked_cores[n_leaked++] = c;
    else
      settle(c, drop_max, g);
  }
  // Beyond the paper: a thin pipe lying on the floor (or on a flat pipe) has its surroundings
  // little more than D below its top; noise and blended rim pixels let growth down onto them and
  // over the floor. A region that leaked is grown again down to D/2 below its core (about the
  // tube's equator, the lowest a camera above sees of it), after the others: it takes no cells
  // from their pipes (15-arc of the zoo: no candidate for a lone 11.5 mm half ring before).
  const float equator_drop = std::min(drop_max, kLeakedDropOfD * d);
  for (int k = 0; k < n_leaked; ++k) {
    const Grown g = room() ? grow_core(leaked_cores[k], long_extent, equator_drop) : Grown::leaked;
    stats.regrown_after_leak += g == Grown::candidate;
    settle(leaked_cores[k], equator_drop, g);
  }
  for (int k = 0; k < n_short; ++k) {
    const bool short_room = room() && stats.short_candidates < cfg.max_short_candidates;
    const Grown g =
        short_room ? grow_core(short_cores[k].core, short_min_extent, short_cores[k].drop) : Grown::too_short;
    if (g == Grown::candidate)
      ++stats.short_candidates;
    else
      count_outcome(g);
  }
  retrying_claimed = true;
  for (int k = 0; k < n_claimed && room(); ++k)
    stats.retried_claimed += grow_core(claimed_cores[k], long_extent, drop_max) == Grown::candidate;
  stats.candidates = int(rb->candidates.size());
  return stats;
}

}  // namespace pipeloc
