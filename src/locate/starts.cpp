#include "locate/starts.hpp"

#include <algorithm>
#include <cmath>

#include "locate/ridge_icp.hpp"

namespace pipeloc {

void reserve_slide(SlideBuffers* buf, const LocatorModel& lm, int max_ridge_points, float ridge_cell_mm) {
  buf->model_ridge.assign(std::size_t(max_ridge_points), Eigen::Vector3f::Zero());
  // The top views span a pipe and a diameter of margin each side, in cells of half the finest ridge.
  const int side = int((lm.extent_l_mm + 4 * lm.tube_d_mm) / (0.5f * ridge_cell_mm)) + 2;
  buf->observed_top.reserve(side);
}

void TopDistance::build(const Eigen::Vector3f* pts, int n, float cell_mm, float cap_mm) {
  cap = cap_mm;
  float lo_x = 1e30f, lo_y = 1e30f, hi_x = -1e30f, hi_y = -1e30f;
  for (int k = 0; k < n; ++k)
    lo_x = std::min(lo_x, pts[k].x()), lo_y = std::min(lo_y, pts[k].y()), hi_x = std::max(hi_x, pts[k].x()),
    hi_y = std::max(hi_y, pts[k].y());
  if (n == 0) lo_x = lo_y = hi_x = hi_y = 0;
  origin_x = lo_x - cap, origin_y = lo_y - cap;
  // A wider set than the buffer was sized for gets coarser cells, not a bigger buffer.
  const float span = std::max(hi_x - lo_x, hi_y - lo_y) + 2 * cap;
  cell = std::max(cell_mm, span / float(capacity_side - 1));
  width = std::min(capacity_side, int((hi_x - lo_x + 2 * cap) / cell) + 1);
  height = std::min(capacity_side, int((hi_y - lo_y + 2 * cap) / cell) + 1);
  std::fill_n(d.begin(), std::size_t(width) * height, cap);
  const int r = int(cap / cell) + 1;
  for (int k = 0; k < n; ++k) {
    const int ci = int((pts[k].x() - origin_x) / cell), cj = int((pts[k].y() - origin_y) / cell);
    for (int j = std::max(0, cj - r); j <= std::min(height - 1, cj + r); ++j)
      for (int i = std::max(0, ci - r); i <= std::min(width - 1, ci + r); ++i) {
        const float dx = origin_x + (float(i) + 0.5f) * cell - pts[k].x();
        const float dy = origin_y + (float(j) + 0.5f) * cell - pts[k].y();
        float& v = d[std::size_t(j) * width + i];
        v = std::min(v, std::sqrt(dx * dx + dy * dy));
      }
  }
}

StartSet prepare_starts(const LocatorModel& lm, const LocateConfig& cfg) {
  StartSet set;
  set.cell_mm = float(std::max(cfg.icp_probe_cell_mm, cfg.ridge_cell_mm));
  const int capacity = int(3 * (lm.extent_l_mm + 2 * lm.tube_d_mm) / set.cell_mm) + 16;
  RidgeBuffers rb;
  reserve_ridge(&rb, lm.extent_l_mm + 2 * lm.tube_d_mm, set.cell_mm, int(lm.ridge_samples.size()));
  std::vector<Eigen::Vector3f> ridge(std::size_t(capacity), Eigen::Vector3f::Zero());
  const int side = int((lm.extent_l_mm + 4 * lm.tube_d_mm) / set.cell_mm) + 2;
  const Eigen::Vector2f x_axis = Eigen::Vector2f::UnitX();
  set.ridge_begin.push_back(0);
  for (int dir = 0; dir < 2; ++dir)
    for (std::size_t k = 0; k < lm.canonical_starts.size(); ++k)
      for (int y = 0; y < lm.yaw_offsets; ++y) {
        Pose turn = Pose::Identity();
        turn.linear() =
            Eigen::AngleAxisd(dir * M_PI + lm.yaw_offset_rad(y), Eigen::Vector3d::UnitZ()).toRotationMatrix();
        const Pose pose = turn * lm.canonical_starts[k];
        const int n = posed_model_ridge(lm, pose, x_axis, set.cell_mm, cfg, &rb, ridge.data(), capacity);
        const Pose to_model = pose.inverse();
        for (int i = 0; i < n; ++i)
          set.ridge_model.push_back((to_model * ridge[std::size_t(i)].cast<double>()).cast<float>());
        set.ridge_begin.push_back(int(set.ridge_model.size()));
        set.top.emplace_back();
        set.top.back().reserve(side);
        set.top.back().build(ridge.data(), n, set.cell_mm, lm.tube_d_mm);
        set.pose.push_back(pose);
      }
  return set;
}

SlidStart slide_start(const LocatorModel& lm, const StartSet& starts, int s, const Pose& axis_to_bin,
                      const Eigen::Vector3f* obs_axis, int n_obs, const LocateConfig& cfg, SlideBuffers* buf,
                      float along_mm) {
  SlidStart out;
  out.start = s;
  out.pose = axis_to_bin * starts.pose[std::size_t(s)];
  const int nm = starts.ridge_count(s);
  if (nm == 0 || n_obs == 0) return out;
  const Eigen::Matrix3f r = out.pose.linear().cast<float>();
  const Eigen::Vector3f t = out.pose.translation().cast<float>();
  const Eigen::Vector3f* ridge = starts.ridge(s);
  for (int i = 0; i < nm; ++i) buf->model_ridge[std::size_t(i)] = r * ridge[i] + t;
  const TopDistance& model_top = starts.top[std::size_t(s)];
  const float d = lm.tube_d_mm;
  const float step = std::max(float(cfg.start_slide_step_of_d) * d, float(cfg.zbuffer_pixel_mm));
  const int n_across = cfg.slide_starts ? int(lm.slide_across_mm / step) : 0;
  const int n_along = cfg.slide_starts ? int(along_mm / (2 * step)) : 0;
  // Offsets are along (x) and across (y) the observed axis: in the axis frame, and turned into the bin.
  const Eigen::Vector2f along = axis_to_bin.linear().col(0).head<2>().cast<float>().normalized();
  const Eigen::Vector2f across(-along.y(), along.x());
  float best = 1e30f;
  Eigen::Vector2f best_offset = Eigen::Vector2f::Zero();
  for (int a = -n_along; a <= n_along; ++a)
    for (int b = -n_across; b <= n_across; ++b) {
      const float oa = float(2 * a) * step, ob = float(b) * step;
      const Eigen::Vector2f offset = oa * along + ob * across;
      float m2o = 0, o2m = 0;
      for (int i = 0; i < nm; ++i) {
        const Eigen::Vector3f& p = buf->model_ridge[std::size_t(i)];
        m2o += buf->observed_top.at(p.x() + offset.x(), p.y() + offset.y());
      }
      // The other half only adds: an offset already beyond the best (and its tie band) is done.
      if (0.5f * (m2o / float(nm)) > best + 1e-4f) continue;
      for (int j = 0; j < n_obs; ++j) o2m += model_top.at(obs_axis[j].x() - oa, obs_axis[j].y() - ob);
      const float cost = 0.5f * (m2o / float(nm) + o2m / float(n_obs));
      // Ties go to the smaller move (the measured centres agree when the whole pipe is seen).
      if (cost < best - 1e-4f || (cost <= best + 1e-4f && offset.norm() < best_offset.norm()))
        best = std::min(best, cost), best_offset = offset;
    }
  out.pose.translation().head<2>() += best_offset.cast<double>();
  out.cost_mm = best;
  return out;
}

}  // namespace pipeloc
