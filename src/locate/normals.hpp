// II-A: normals by plane fitting z = a x + b y + c over a square neighbourhood of Z-buffer cells.
#pragma once

#include <vector>

#include "locate/zbuffer.hpp"

namespace pipeloc {

struct NormalMap {
  Image<Eigen::Vector3f> n;    // unit, Z up; zero where there is no normal
  std::vector<double> column;  // running column sums, 9 per cell column (fixed size)
};

void reserve_normals(NormalMap* nm, const ZBuffer& zb);

// window_cells odd; cells with fewer than min_valid valid neighbours get no normal.
void compute_normals(const ZBuffer& zb, int window_cells, int min_valid, NormalMap* nm);

}  // namespace pipeloc
