// II-A: observed points in the bin frame (Z up) stored in a Z-buffer with square cells:
// zimg[round(Y)][round(X)] = Z, the highest point per cell.
#pragma once

#include <cmath>
#include <limits>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "locate/locate_config.hpp"

namespace pipeloc {

// Round to nearest without a libm call (hot loops over every pixel and cell).
inline long round_nearest(float v) { return long(v + std::copysign(0.5f, v)); }

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

// The depth pixels in the bin frame, between the two steps of filling a Z-buffer; both steps
// work in bands (of image rows, then of buffer rows) that can run on different threads.
struct ZBufferPoints {
  struct Extent {
    float lo_x = 1e30f, lo_y = 1e30f, hi_x = -1e30f, hi_y = -1e30f;
    int valid = 0;
  };
  // Per image row: the least and greatest y of its valid points (bin) and their widest footprint
  // half-width in cells (< 0: none valid), so that a band of buffer rows skips the image rows
  // that cannot reach it.
  struct RowSpan {
    float lo_y = 0, hi_y = 0, half = -1;
  };
  int width = 0, height = 0;  // of the depth image
  std::vector<Eigen::Vector4f>
      p;                     // per depth pixel: x, y, z (bin), footprint half-width in cells (< 0: none)
  std::vector<Extent> band;  // per image-row band: extent of its valid points
  std::vector<RowSpan> row;
};
void reserve_zbuffer_points(ZBufferPoints* pts, int width, int height, int bands);

// Step 1, image rows [v0, v1) as band `band`: each valid pixel in the bin frame, with the
// half-width of its footprint in buffer cells (so cells finer than the sensor's pixels are not
// left with holes). Points outside `roi` (when on) count as no reading.
void zbuffer_points_rows(const Image<float>& depth_mm, const Intrinsics& k, const Pose& bin_to_cam,
                         double pixel_mm, int v0, int v1, int band, ZBufferPoints* pts,
                         const RegionOfInterest& roi = {});
// Between the steps: places the buffer over the bands' extent (its middle, when larger than the
// buffer). Returns the number of valid depth pixels.
int place_zbuffer(const ZBufferPoints& pts, int bands, ZBuffer* zb);
// Step 2, buffer rows [j0, j1): cleared, then every point's footprint over them, keeping the highest.
void splat_zbuffer_rows(const ZBufferPoints& pts, int j0, int j1, ZBuffer* zb);

// The three in one band: fills zb from a depth image. Returns the number of valid depth pixels.
int build_zbuffer(const Image<float>& depth_mm, const Intrinsics& k, const Pose& bin_to_cam,
                  ZBufferPoints* pts, ZBuffer* zb);

// Share of pts (bin frame) whose cell holds an observed height more than tol_mm below them: the
// sensor saw through where they would be. Cells with no reading or a higher one say nothing.
float seen_through_share(const ZBuffer& zb, const Eigen::Vector3f* pts, int n, float tol_mm);

// The empty cells still to fill, and the values a pass found for them: one slot per buffer cell
// (a band of rows keeps its holes in its own rows' slots).
struct HoleList {
  std::vector<int> cell;
  std::vector<float> value;
  void reserve(const ZBuffer& zb) {
    cell.assign(zb.z.pixels.size(), 0);
    value.assign(zb.z.pixels.size(), 0.0f);
  }
};

// Fills holes a few cells wide whose neighbours agree within max_spread_mm (glints on a ridge),
// `passes` cells deep.
void fill_small_holes(ZBuffer* zb, int passes, float max_spread_mm, HoleList* holes);
// The same in steps over row bands [j0, j1) (the buffer's border rows and columns are never
// filled): the band's empty cells are listed once (returns their count); per pass, the values of
// those that can be filled are found (returns how many), and once every band has done that,
// written, the rest kept listed (returns how many are left).
int collect_holes_rows(const ZBuffer& zb, int j0, int j1, HoleList* holes);
int fill_holes_pass(const ZBuffer& zb, float max_spread_mm, int j0, int count, HoleList* holes);
int apply_filled(int j0, int count, HoleList* holes, ZBuffer* zb);

}  // namespace pipeloc
