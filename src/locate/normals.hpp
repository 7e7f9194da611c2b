// II-A: normals by plane fitting z = a x + b y + c over a square neighbourhood of Z-buffer cells.
#pragma once

#include <vector>

#include "locate/zbuffer.hpp"

namespace pipeloc {

struct NormalMap {
  Image<Eigen::Vector3f> n;  // unit, Z up; zero where there is no normal
  int bands = 1;             // row bands that may be worked at once
  std::vector<double> sums;  // per band: 9 running column sums and 9 window sums per cell column
};

// A cell without a normal holds zero; a fitted one, (-a, -b, 1) normalised, always has z > 0.
inline bool has_normal(const Eigen::Vector3f& n) { return n.z() != 0; }

// `bands`: how many row bands may be worked at once (each needs its own column sums).
void reserve_normals(NormalMap* nm, const ZBuffer& zb, int bands = 1);

// Rows [j0, j1) only, with band `band` (< the bands reserved) of the scratch sums: bands of one
// Z-buffer can run on different threads.
void compute_normals_rows(const ZBuffer& zb, int window_cells, int min_valid, int j0, int j1, int band,
                          NormalMap* nm);

// window_cells odd; cells with fewer than min_valid valid neighbours get no normal.
void compute_normals(const ZBuffer& zb, int window_cells, int min_valid, NormalMap* nm);

}  // namespace pipeloc
