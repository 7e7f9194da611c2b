#include "service/tried_picks.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {

namespace {

// A surface point of the pose the frame shows: facing the camera (within 60 degrees) and read
// where it lies (within D/2), so that taking the pipe away moves the depth there by at least 3/4 D.
// Where a pixel sees past the pipe (its ends, its rim, what covers it), the pick changes nothing.
bool seen_on_top(const Eigen::Vector3d& c, const Eigen::Vector3d& normal, const Image<float>& depth_mm,
                 const Intrinsics& k, float half_d, int* pixel) {
  if (c.z() <= 0 || normal.dot(c.normalized()) > -0.5) return false;
  const Eigen::Vector2d uv = k.project(c);
  const int x = int(std::lround(uv.x())), y = int(std::lround(uv.y()));
  if (!depth_mm.inside(x, y)) return false;
  const float z = depth_mm.at(x, y);
  if (!(z > 0) || std::abs(double(z) - c.z()) > half_d) return false;
  *pixel = y * depth_mm.width + x;
  return true;
}

}  // namespace

void TriedPicks::handed_out(const Pose& model_to_cam, const Image<float>& depth_mm, const Intrinsics& k,
                            const LocatorModel& lm) {
  last_ = model_to_cam;
  has_last_ = true;
  Footprint& f = last_footprint_;
  f.n = 0;
  const SurfaceSamples& surface = lm.model->surface;
  const std::size_t points = std::min(surface.points.size(), surface.normals.size());
  const float half_d = 0.5f * lm.tube_d_mm;
  // At most kExamined samples spread over the surface; of those the frame shows on top, every
  // take-th, so that the footprint spreads over the whole pipe too (two passes: no allocation).
  const std::size_t stride = std::max<std::size_t>(1, points / kExamined);
  const auto seen = [&](std::size_t i, int* pixel) {
    return seen_on_top(model_to_cam * surface.points[i].cast<double>(),
                       model_to_cam.linear() * surface.normals[i].cast<double>(), depth_mm, k, half_d, pixel);
  };
  int on_top = 0, pixel = 0;
  for (std::size_t i = 0; i < points; i += stride) on_top += seen(i, &pixel);
  const int take = std::max(1, (on_top + kFootprintPx - 1) / kFootprintPx);
  int counted = 0;
  for (std::size_t i = 0; i < points && f.n < kFootprintPx; i += stride) {
    if (!seen(i, &pixel) || counted++ % take != 0) continue;
    f.pixel[std::size_t(f.n)] = pixel;
    f.depth_mm[std::size_t(f.n)] = depth_mm.pixels[std::size_t(pixel)];
    ++f.n;
  }
}

bool TriedPicks::unchanged(const Footprint& f, const Image<float>& depth_mm, float tube_d_mm) {
  if (f.n < kMinFootprintPx) return false;
  const float tolerance = 0.5f * tube_d_mm;
  int same = 0;
  for (int i = 0; i < f.n; ++i) {
    const std::size_t at = std::size_t(f.pixel[std::size_t(i)]);
    if (at >= depth_mm.pixels.size()) continue;  // a frame of another size: nothing reads as before
    const float z = depth_mm.pixels[at];
    same += z > 0 && std::abs(z - f.depth_mm[std::size_t(i)]) <= tolerance;
  }
  return same >= kUnchangedShare * f.n;
}

bool TriedPicks::next_frame(const Image<float>& depth_mm, float tube_d_mm) {
  int kept = 0;
  for (int i = 0; i < count_; ++i)
    if (unchanged(footprints_[std::size_t(i)], depth_mm, tube_d_mm)) {
      poses_[std::size_t(kept)] = poses_[std::size_t(i)];
      footprints_[std::size_t(kept)] = footprints_[std::size_t(i)];
      ++kept;
    }
  count_ = kept;
  const bool took_nothing = has_last_ && unchanged(last_footprint_, depth_mm, tube_d_mm);
  if (took_nothing) {
    if (count_ == Locator::kMaxTried) {  // the oldest goes
      std::move(poses_.begin() + 1, poses_.end(), poses_.begin());
      std::move(footprints_.begin() + 1, footprints_.end(), footprints_.begin());
      --count_;
    }
    poses_[std::size_t(count_)] = last_;
    footprints_[std::size_t(count_)] = last_footprint_;
    ++count_;
  }
  has_last_ = false;
  return took_nothing;
}

}  // namespace pipeloc
