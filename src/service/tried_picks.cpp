#include "service/tried_picks.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {

void TriedPicks::handed_out(const Pose& model_to_cam, const Image<float>& depth_mm, const Intrinsics& k,
                            const LocatorModel& lm) {
  last_ = model_to_cam;
  has_last_ = true;
  Footprint& f = last_footprint_;
  f.n = 0;
  const std::size_t points = lm.check_points.size();
  const std::size_t step = std::max<std::size_t>(1, points / kFootprintPx);
  for (std::size_t i = 0; i < points && f.n < kFootprintPx; i += step) {
    const Eigen::Vector3d c = model_to_cam * lm.check_points[i].cast<double>();
    if (c.z() <= 0) continue;
    const Eigen::Vector2d uv = k.project(c);
    const int x = int(std::lround(uv.x())), y = int(std::lround(uv.y()));
    if (!depth_mm.inside(x, y)) continue;
    const float z = depth_mm.at(x, y);
    if (!(z > 0)) continue;
    f.pixel[std::size_t(f.n)] = y * depth_mm.width + x;
    f.depth_mm[std::size_t(f.n)] = z;
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
