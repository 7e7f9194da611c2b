// II-A: observed points in the bin frame (Z up) stored in a Z-buffer with square cells:
// zimg[round(Y)][round(X)] = Z, the highest point per cell.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"

namespace pipeloc {

// Round to nearest without a libm call (hot loops over every pixel and cell).
inline long round_nearest(float v) { return long(v + (v >= 0 ? 0.5f : -0.5f)); }

struct ZBuffer {
  double origin_x_mm = 0, origin_y_mm = 0;  // centre of cell (0, 0)
  double pixel_mm = 1;
  int width = 0, height = 0;  // cells in use (<= capacity of z)
  Image<float> z;             // height, NaN where nothing was seen

  static constexpr float kEmpty = std::numeric_limits<float>::quiet_NaN();
  bool valid(int i, int j) const {
    return i >= 0 && j >= 0 && i < width && j < height && !std::isnan(z.at(i, j));
  }
  Eigen::Vector3f point(int i, int j) const {
    return {float(origin_x_mm + i * pixel_mm), float(origin_y_mm + j * pixel_mm), z.at(i, j)};
  }
  int index(int i, int j) const { return j * z.width + i; }
};

// The bin frame: world of cam_R_w2c/cam_t_w2c when given; otherwise the camera frame turned
// half a turn about x, so that Z points up towards the camera as in the world frame.
Pose bin_to_camera(const CameraInfo& camera);

// Allocates the buffer once for the largest configured area.
void reserve_zbuffer(ZBuffer* zb, double max_side_mm, double pixel_mm);

// Fills zb from a depth image. Each point covers its pixel's footprint, so cells finer than the
// sensor's pixels are not left with holes. Returns the number of valid depth pixels.
int build_zbuffer(const Image<float>& depth_mm, const Intrinsics& k, const Pose& bin_to_cam, ZBuffer* zb);

// Share of pts (bin frame) whose cell holds an observed height more than tol_mm below them: the
// sensor saw through where they would be. Cells with no reading or a higher one say nothing.
float seen_through_share(const ZBuffer& zb, const Eigen::Vector3f* pts, int n, float tol_mm);

// Fills holes a few cells wide whose neighbours agree within max_spread_mm (glints on a ridge),
// `passes` cells deep. scratch: one float per buffer cell.
void fill_small_holes(ZBuffer* zb, int passes, float max_spread_mm, std::vector<float>* scratch);

}  // namespace pipeloc
