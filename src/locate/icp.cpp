#include "locate/icp.hpp"

#include <emmintrin.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

int model_ridge(const LocatorModel& lm, const Pose& pose, const Eigen::Vector2f& axis, float cell_mm,
                const LocateConfig& cfg, IcpBuffers* buf) {
  PosedPoints samples;
  samples.points = lm.ridge_samples.data();
  samples.normals = lm.ridge_normals.data();
  samples.count = int(lm.ridge_samples.size());
  samples.stride = ridge_sample_stride(cell_mm, cfg);
  samples.columns = lm.ridge_columns_for(samples.stride);
  samples.to_bin = pose;
  return extract_zridge(samples, axis, cell_mm, kRidgeMinRunOfD * lm.tube_d_mm, &buf->ridge, buf->model_ridge.data(),
                        int(buf->model_ridge.size()), cfg.match_surface);
}

// Nearest partners both ways between the model's ridge (buf->model_ridge[0..nm)) and the observed
// one, laid out in buf->observed_columns: buf->model_to/model_d2 and buf->observed_to/observed_d2.
void pair_up(int nm, IcpBuffers* buf) {
  buf->observed_columns.nearest_both_ways(buf->model_ridge.data(), nm, buf->model_to.data(),
                                          buf->model_d2.data(), buf->observed_to.data(),
                                          buf->observed_d2.data());
}

// Mean of min(distance, cap) over squared distances d2[0..n) (cap if none); *matched: those under cap.
float truncated_mean(const float* d2, int n, float cap, int* matched) {
  if (n == 0) return cap;
  float sum = 0;
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const float d = std::sqrt(d2[i]);
    if (d < cap) ++m;
    sum += std::min(d, cap);
  }
  if (matched) *matched = m;
  return sum / float(n);
}

// Squared distances from q to points j..j+3 of the columns, summed as the one-at-a-time tail sums
// them ((p - q)^2 equals (q - p)^2 exactly, so either side's search gets the same floats).
inline __m128 distances4(const float* xs, const float* ys, const float* zs, int j, __m128 qx, __m128 qy,
                         __m128 qz) {
  const __m128 dx = _mm_sub_ps(_mm_loadu_ps(xs + j), qx), dy = _mm_sub_ps(_mm_loadu_ps(ys + j), qy),
               dz = _mm_sub_ps(_mm_loadu_ps(zs + j), qz);
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
}

// Per lane, the least distance so far and the first index at it: a later one replaces it only
// when strictly closer.
inline void keep_first_least(__m128 d, __m128i index4, __m128* low4, __m128i* at4) {
  const __m128i closer = _mm_castps_si128(_mm_cmplt_ps(d, *low4));
  *low4 = _mm_min_ps(d, *low4);
  *at4 = _mm_or_si128(_mm_and_si128(closer, index4), _mm_andnot_si128(closer, *at4));
}

// The least of the lanes' distances, and of the points at it the first (-1 if none).
inline float first_least_of_lanes(__m128 low4, __m128i at4, int* best) {
  alignas(16) float lanes[4];
  alignas(16) int lane_at[4];
  _mm_store_ps(lanes, low4);
  _mm_store_si128(reinterpret_cast<__m128i*>(lane_at), at4);
  float low = 1e30f;
  *best = -1;
  for (int l = 0; l < 4; ++l)
    if (lanes[l] < low || (lanes[l] == low && lane_at[l] >= 0 && lane_at[l] < *best))
      low = lanes[l], *best = lane_at[l];
  return low;
}

}  // namespace

// nearest() on columns, four points at a time: each lane keeps its least distance and the first
// point at it; the lanes then give the least, and of the points at it the first. Same sums in the
// same order, same answer.
int PointColumns::nearest(const Eigen::Vector3f& q, float* d2) const {
  const float *xs = x.data(), *ys = y.data(), *zs = z.data();
  const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
  __m128 low4 = _mm_set1_ps(1e30f);
  __m128i at4 = _mm_set1_epi32(-1), index4 = _mm_setr_epi32(0, 1, 2, 3);
  const __m128i four = _mm_set1_epi32(4);
  int i = 0;
  for (; i + 4 <= n; i += 4, index4 = _mm_add_epi32(index4, four))
    keep_first_least(distances4(xs, ys, zs, i, qx, qy, qz), index4, &low4, &at4);
  int best;
  float low = first_least_of_lanes(low4, at4, &best);
  for (; i < n; ++i) {  // the last few lie after every lane's
    const float dx = xs[i] - q.x(), dy = ys[i] - q.y(), dz = zs[i] - q.z();
    const float d = dx * dx + dy * dy + dz * dz;
    if (d < low) low = d, best = i;
  }
  *d2 = low;
  return low < 1e30f ? best : -1;
}

void PointColumns::nearest_both_ways(const Eigen::Vector3f* a, int na, int* a_to, float* a_d2, int* b_to,
                                     float* b_d2) const {
  const float *xs = x.data(), *ys = y.data(), *zs = z.data();
  std::fill_n(b_d2, n, 1e30f);
  std::fill_n(b_to, n, -1);
  const __m128i four = _mm_set1_epi32(4);
  for (int i = 0; i < na; ++i) {
    const Eigen::Vector3f& q = a[i];
    const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
    const __m128i i4 = _mm_set1_epi32(i);
    __m128 low4 = _mm_set1_ps(1e30f);
    __m128i at4 = _mm_set1_epi32(-1), index4 = _mm_setr_epi32(0, 1, 2, 3);
    int j = 0;
    for (; j + 4 <= n; j += 4, index4 = _mm_add_epi32(index4, four)) {
      const __m128 d = distances4(xs, ys, zs, j, qx, qy, qz);
      keep_first_least(d, index4, &low4, &at4);
      // b's side: a strictly closer a[i] replaces the one held, so ties keep the first
      __m128 held = _mm_loadu_ps(b_d2 + j);
      __m128i held_to = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b_to + j));
      keep_first_least(d, i4, &held, &held_to);
      _mm_storeu_ps(b_d2 + j, held);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(b_to + j), held_to);
    }
    int best;
    float low = first_least_of_lanes(low4, at4, &best);
    for (; j < n; ++j) {
      const float dx = xs[j] - q.x(), dy = ys[j] - q.y(), dz = zs[j] - q.z();
      const float d = dx * dx + dy * dy + dz * dz;
      if (d < low) low = d, best = j;
      if (d < b_d2[j]) b_d2[j] = d, b_to[j] = i;
    }
    a_d2[i] = low;
    a_to[i] = low < 1e30f ? best : -1;
  }
  // (b_to[j] stays -1 unless some a[i] came strictly under 1e30: no clean-up needed)
}

void PointColumns::reserve(int capacity) {
  x.assign(std::size_t(capacity), 0.0f);
  y.assign(std::size_t(capacity), 0.0f);
  z.assign(std::size_t(capacity), 0.0f);
  n = 0;
}

bool PointColumns::assign(const Eigen::Vector3f* p, int count) {
  if (count > int(x.size())) return false;
  for (int i = 0; i < count; ++i)
    x[std::size_t(i)] = p[i].x(), y[std::size_t(i)] = p[i].y(), z[std::size_t(i)] = p[i].z();
  n = count;
  return true;
}

void reserve_icp(IcpBuffers* buf, const LocatorModel& lm, int max_ridge_points, float ridge_cell_mm,
                 int max_region_points) {
  buf->model_ridge.assign(std::size_t(max_ridge_points), Eigen::Vector3f::Zero());
  buf->src.assign(std::size_t(2 * max_ridge_points), Eigen::Vector3f::Zero());
  buf->dst.assign(std::size_t(2 * max_ridge_points), Eigen::Vector3f::Zero());
  buf->observed_columns.reserve(max_ridge_points);
  for (auto* to : {&buf->model_to, &buf->observed_to}) to->assign(std::size_t(max_ridge_points), -1);
  for (auto* d2 : {&buf->model_d2, &buf->observed_d2}) d2->assign(std::size_t(max_ridge_points), 0.0f);
  // The top views span a pipe and a diameter of margin each side, in cells of half the finest ridge.
  const int side = int((lm.extent_l_mm + 4 * lm.tube_d_mm) / (0.5f * ridge_cell_mm)) + 2;
  buf->observed_top.reserve(side);
  reserve_ridge(&buf->ridge, lm.extent_l_mm + 2 * lm.tube_d_mm, ridge_cell_mm,
                std::max(max_region_points, int(lm.ridge_samples.size())));
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
  IcpBuffers buf;
  const int capacity = int(3 * (lm.extent_l_mm + 2 * lm.tube_d_mm) / set.cell_mm) + 16;
  reserve_icp(&buf, lm, capacity, set.cell_mm);
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
        const int n = model_ridge(lm, pose, x_axis, set.cell_mm, cfg, &buf);
        const Pose to_model = pose.inverse();
        for (int i = 0; i < n; ++i)
          set.ridge_model.push_back(
              (to_model * buf.model_ridge[std::size_t(i)].cast<double>()).cast<float>());
        set.ridge_begin.push_back(int(set.ridge_model.size()));
        set.top.emplace_back();
        set.top.back().reserve(side);
        set.top.back().build(buf.model_ridge.data(), n, set.cell_mm, lm.tube_d_mm);
        set.pose.push_back(pose);
      }
  return set;
}

SlidStart slide_start(const LocatorModel& lm, const StartSet& starts, int s, const Pose& axis_to_bin,
                      const Eigen::Vector3f* obs_axis, int n_obs, const LocateConfig& cfg, IcpBuffers* buf) {
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
  const int n_across = int(lm.slide_across_mm / step), n_along = int(lm.slide_along_mm / (2 * step));
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

Pose fit_rigid(const Eigen::Vector3f* src, const Eigen::Vector3f* dst, int n) {
  Eigen::Vector3d cs = Eigen::Vector3d::Zero(), cd = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) cs += src[i].cast<double>(), cd += dst[i].cast<double>();
  cs /= n;
  cd /= n;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) h += (src[i].cast<double>() - cs) * (dst[i].cast<double>() - cd).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  Pose out = Pose::Identity();
  out.linear() = svd.matrixV() * d * svd.matrixU().transpose();
  out.translation() = cd - out.linear() * cs;
  return out;
}

namespace {

// ridge_icp's iterations on the observed ridge, laid out in buf->observed_columns (cell_mm > 0).
RidgeFit iterate_ridge_icp(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* obs, int n_obs,
                           const Eigen::Vector2f& axis, const LocateConfig& cfg, int max_iterations,
                           IcpBuffers* buf, float gate_mm, float cell_mm, const Eigen::Vector3f* start_ridge,
                           int start_ridge_count) {
  RidgeFit fit;
  fit.pose = start;
  const float d = lm.tube_d_mm;
  // Correspondences farther than this are dropped; it shrinks from a third of the pipe to D/2.
  float gate = gate_mm > 0 ? gate_mm : std::max(lm.extent_l_mm / 3, d);
  for (int it = 0; it < max_iterations; ++it) {
    fit.iterations = it + 1;
    int nm = 0;  // 2.2.1
    if (it == 0 && start_ridge) {
      const Eigen::Matrix3f r = fit.pose.linear().cast<float>();
      const Eigen::Vector3f t = fit.pose.translation().cast<float>();
      nm = std::min(start_ridge_count, int(buf->model_ridge.size()));
      for (int i = 0; i < nm; ++i) buf->model_ridge[std::size_t(i)] = r * start_ridge[i] + t;
    } else {
      nm = model_ridge(lm, fit.pose, axis, cell_mm, cfg, buf);
    }
    pair_up(nm, buf);
    int pairs = 0;
    for (int i = 0; i < nm; ++i) {  // 2.2.2
      const int j = buf->model_to[std::size_t(i)];
      if (j < 0 || buf->model_d2[std::size_t(i)] > gate * gate) continue;
      buf->src[pairs] = buf->model_ridge[i];
      buf->dst[pairs] = obs[j];
      ++pairs;
    }
    // Both ways: observed ridge points pull too, so the model cannot slide along the ridge
    // towards parts that were not observed.
    for (int j = 0; j < n_obs && pairs < int(buf->src.size()); ++j) {
      const int i = buf->observed_to[std::size_t(j)];
      if (i < 0 || buf->observed_d2[std::size_t(j)] > gate * gate) continue;
      buf->src[pairs] = buf->model_ridge[i];
      buf->dst[pairs] = obs[j];
      ++pairs;
    }
    if (pairs < 6) break;
    const Pose delta = fit_rigid(buf->src.data(), buf->dst.data(), pairs);  // 2.2.3
    fit.pose = delta * fit.pose;
    gate = std::max(0.5f * d, gate * 0.7f);
    const double moved =
        delta.translation().norm() + Eigen::AngleAxisd(delta.linear()).angle() * lm.extent_l_mm / 2;
    if (moved < cfg.icp_converged_mm && gate <= 0.5f * d) break;
  }
  fit.gate_mm = gate;
  return fit;
}

// ridge_icp's closing evaluation of fit->pose: cost_mm, matched, model_ridge_points (the model's
// ridge stays in buf->model_ridge).
void score_ridge_fit(const LocatorModel& lm, int n_obs, const Eigen::Vector2f& axis, const LocateConfig& cfg,
                     IcpBuffers* buf, float cell_mm, RidgeFit* fit) {
  const int nm = model_ridge(lm, fit->pose, axis, cell_mm, cfg, buf);
  fit->model_ridge_points = nm;
  const float cap = 0.5f * lm.tube_d_mm;
  pair_up(nm, buf);
  const float m2o = truncated_mean(buf->model_d2.data(), nm, cap, &fit->matched);
  const float o2m = truncated_mean(buf->observed_d2.data(), n_obs, cap, nullptr);
  fit->cost_mm = 0.5f * (m2o + o2m);
}

}  // namespace

RidgeFit ridge_icp_steps(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* obs, int n_obs,
                         const Eigen::Vector2f& axis, const LocateConfig& cfg, int max_iterations,
                         IcpBuffers* buf, float gate_mm, float cell_mm, const Eigen::Vector3f* start_ridge,
                         int start_ridge_count) {
  if (cell_mm <= 0) cell_mm = float(cfg.ridge_cell_mm);
  RidgeFit unfit;
  unfit.pose = start;
  if (!buf->observed_columns.assign(obs, n_obs)) return unfit;
  return iterate_ridge_icp(lm, start, obs, n_obs, axis, cfg, max_iterations, buf, gate_mm, cell_mm,
                           start_ridge, start_ridge_count);
}

RidgeFit ridge_icp(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* obs, int n_obs,
                   const Eigen::Vector2f& axis, const LocateConfig& cfg, int max_iterations, IcpBuffers* buf,
                   float gate_mm, float cell_mm, const Eigen::Vector3f* start_ridge, int start_ridge_count) {
  if (cell_mm <= 0) cell_mm = float(cfg.ridge_cell_mm);
  RidgeFit fit = ridge_icp_steps(lm, start, obs, n_obs, axis, cfg, max_iterations, buf, gate_mm, cell_mm,
                                 start_ridge, start_ridge_count);
  // The steps laid out the observed ridge, which the evaluation pairs with again; a ridge larger
  // than the columns were reserved for was not laid out (their count is then below n_obs): no fit.
  if (buf->observed_columns.n == n_obs) score_ridge_fit(lm, n_obs, axis, cfg, buf, cell_mm, &fit);
  return fit;
}

RefineResult refine_on_surface(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* obs, int n,
                               const LocateConfig& cfg) {
  RefineResult res;
  res.pose = start;
  const float inlier = float(cfg.refine_inlier_mm);
  // Coarse to fine: all but the last kFineIterations use every third point; the last (and the
  // reported inliers and rms) all of them.
  constexpr int kFineIterations = 3, kCoarseStride = 3;
  const int fine_from = std::max(0, cfg.refine_iterations - kFineIterations);
  for (int it = 0; it < cfg.refine_iterations; ++it) {
    const int stride = it < fine_from ? kCoarseStride : 1;
    const Eigen::Matrix3f r = res.pose.linear().cast<float>();
    const Eigen::Vector3f t = res.pose.translation().cast<float>();
    const Eigen::Matrix3f rt = r.transpose();
    const Eigen::Vector3f c = r * lm.centroid + t;  // linearise about the model's centroid
    Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    int inliers = 0;
    double sq = 0;
    // Look-ups first, a batch at a time, then the sums: the batch's cache misses overlap instead
    // of each waiting for the last.
    constexpr int kBatch = 16;
    Eigen::Vector3f batch_q[kBatch];
    const LocatorModel::Sample* batch_s[kBatch];
    for (int i0 = 0; i0 < n; i0 += stride * kBatch) {
      const int in_batch = std::min(kBatch, (n - i0 + stride - 1) / stride);
      for (int k = 0; k < in_batch; ++k) {
        batch_q[k] = rt * (obs[i0 + k * stride] - t);  // observed point in the model frame
        batch_s[k] = lm.nearest_sample(batch_q[k]);
      }
      for (int k = 0; k < in_batch; ++k) {
        const Eigen::Vector3f& q = batch_q[k];
        const LocatorModel::Sample* s = batch_s[k];
        if (!s) continue;
        const Eigen::Vector3f diff = q - s->p;
        if (diff.squaredNorm() > inlier * inlier) continue;
        const Eigen::Vector3f nw = r * s->n;
        const Eigen::Vector3f mw = r * s->p + t - c;
        const float res_i = nw.dot(r * diff);  // observed minus model, along the normal
        // Moving the model by (w, v) changes the model point by w x m + v.
        Eigen::Matrix<double, 6, 1> j;
        j.head<3>() = mw.cross(nw).cast<double>();
        j.tail<3>() = nw.cast<double>();
        const double w = std::abs(res_i) < 1.5f ? 1.0 : 1.5 / std::abs(res_i);  // Huber
        const Eigen::Matrix<double, 6, 1> wj = w * j;
        // The lower triangle only (the solve reads no more); mirrored once per iteration.
        for (int col = 0; col < 6; ++col)
          for (int row = col; row < 6; ++row) a(row, col) += wj(row) * j(col);
        b += wj * double(res_i);
        ++inliers;
        sq += double(res_i) * res_i;
      }
    }
    a.triangularView<Eigen::StrictlyUpper>() = a.transpose();
    res.inliers = inliers * stride;  // about: only the fine iterations count them all
    res.rms_mm = inliers ? float(std::sqrt(sq / inliers)) : 0.f;
    if (inliers < 12) break;
    const Eigen::Matrix<double, 6, 1> x = a.ldlt().solve(b);
    if (!x.allFinite()) break;
    Pose delta = Pose::Identity();
    const double angle = x.head<3>().norm();
    if (angle > 1e-12) delta.linear() = Eigen::AngleAxisd(angle, x.head<3>() / angle).toRotationMatrix();
    const Eigen::Vector3d cd = c.cast<double>();
    delta.translation() = cd - delta.linear() * cd + x.tail<3>();
    res.pose = delta * res.pose;
    if (x.tail<3>().norm() < 0.01 && angle < 1e-4) {
      if (stride == 1) break;
      it = fine_from - 1;  // converged on the subset: go on to the fine iterations
    }
  }
  return res;
}

}  // namespace pipeloc
