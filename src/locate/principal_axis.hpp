// III: the pipe's principal direction from the widths of cross-sections while the scan
// direction turns, and the initial position on the line through the core centroid.
#pragma once

#include <cstdint>
#include <vector>

#include "locate/locate_config.hpp"
#include "locate/zbuffer.hpp"

namespace pipeloc {

struct AxisEstimate {
  Eigen::Vector2f axis = Eigen::Vector2f::UnitX();   // unit, in the bin's XY plane
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();  // mid-point of the region along the axis line
  int best_count = 0;                                // cross-sections of width 0.9R..1.0R at the best angle
  float scan_deg = 0;                                // scan direction with most such sections
};

struct AxisBuffers {
  std::vector<float> column, row;  // per region cell: its buffer coordinates; capacity: the largest region
  std::vector<int> line, along;    // per region cell, per scan direction
  std::vector<int> start;          // per scan line: where its cells begin in `sorted`
  std::vector<int> by_along;       // per along-position (quarter cells): where its cells begin in `order`
  std::vector<int> order;          // cells in order along the scan direction
  std::vector<int> sorted;         // cells' along-positions grouped by line, in order along each
};
// Sizes the buffers for regions of up to max_cells cells of a Z-buffer up to w x h cells.
void reserve_axis(AxisBuffers* buf, int max_cells, int w, int h);

// Number of runs ("cross-sections") of region cells (buffer columns and rows, cells of pixel_mm)
// along scan lines in direction theta whose width lies in [min_w, max_w] mm.
int count_sections(const float* column, const float* row, int count, float pixel_mm, float theta_rad,
                   float min_w, float max_w, AxisBuffers* buf);

AxisEstimate estimate_axis(const ZBuffer& zb, const int* cells, int count,
                           const Eigen::Vector3f& core_centroid, const LocateConfig& cfg, float tube_d_mm,
                           AxisBuffers* buf);

}  // namespace pipeloc
