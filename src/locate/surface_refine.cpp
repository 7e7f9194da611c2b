#include "locate/surface_refine.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

// Residuals beyond this (mm) weigh less (Huber): a point of a neighbouring pipe inside the inlier
// distance does not pull the fit. A fixed length, not the noise's: about one sigma of the zoo's
// active-stereo sensor at 0.7 m (1.4 mm measured), under one of the Kinect-class sensor's at 1 m
// (2.5 mm). A weight of 1.345 sigma of each frame's measured noise was measured, in every
// refinement and in the polish only, and gave no gain (docs/experiments.md, "Turns about a short
// pipe's length, holes, the sensor's shadows; why the coil's bins stop").
constexpr float kHuberMm = 1.5f;
// Fewer inliers than this cannot hold six degrees of freedom against the noise: stop.
constexpr int kMinInliers = 12;
// Levenberg-Marquardt damping, a share of each unknown's own weight. Where the points fix a
// motion poorly (a straight tube's slide along and turn about its axis, a ring's turn about its
// centre, a short bend's turn about its length) the normal equations are near singular, and the
// undamped solve moved such a pose metres in one step (a torus-like ring of the dev set, 58 such
// steps in one frame). Not for arcs and coils: their slides along themselves are judged apart
// (judge_slides), and damped they kept slid poses the image could not tell from their pipe
// (docs/experiments.md, "A straight tube's refinement damped"; "The refinement pairs points with
// the surface the camera sees").
constexpr double kDamping = 1e-3;

// Where the ray from `eye` through q first meets the cylinder of `radius` round a sample's tube
// (its axis through the sample's centre, along its direction `dir`), if it does so within `reach`
// of q and within a radius of the sample along the tube: *partner and its outward *normal. A
// point's depth noise lies along that ray, so it lies before or behind that partner by the noise
// alone; the nearest sample instead moves up the tube's side with a noisy point, and on a thin
// tube the fit then sits nearer the camera (docs/experiments.md, "Points paired along the
// camera's rays").
bool ray_meets_tube(const Eigen::Vector3f& eye, const Eigen::Vector3f& q, const LocatorModel::Sample& s,
                    const Eigen::Vector3f& dir, float radius, float reach, Eigen::Vector3f* partner,
                    Eigen::Vector3f* normal) {
  // The ray as q + u (q - eye): u = 0 at q, -1 at the eye. Measured from q and from the tube's
  // axis near it, the short lengths keep their digits, and nothing is normalised.
  const Eigen::Vector3f d = q - eye;
  const Eigen::Vector3f w = q - s.p + radius * s.n;  // from the tube's axis
  const float dd = d.dot(dir), wd = w.dot(dir);
  const Eigen::Vector3f dp = d - dd * dir, wp = w - wd * dir;
  const float qa = dp.squaredNorm(), qb = wp.dot(dp), qc = wp.squaredNorm() - radius * radius;
  const float disc = qb * qb - qa * qc;
  if (disc < 0 || qa < 1e-12f * d.squaredNorm() || dir.isZero()) return false;
  const float u = (-qb - std::sqrt(disc)) / qa;  // the nearer meeting: the side it faces
  const float along = wd + u * dd;
  if (std::abs(along) > radius || u * u * d.squaredNorm() > reach * reach) return false;
  *partner = q + u * d;
  *normal = (w + u * d - along * dir) * (1.f / radius);
  return true;
}

}  // namespace

RefineResult refine_on_surface(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* obs, int n,
                               const LocateConfig& cfg, const Eigen::Vector3f& camera_bin) {
  RefineResult res;
  const bool slides = !lm.straight && !lm.slides.empty();  // an arc or a coil
  // Points read as the camera saw them, but not for a pipe that slides along itself, which its
  // ends place: there facing only cost an arc and a coil (surface_refine.hpp), and along the rays a
  // straight tube of the zoo (seed 20) was handed out 26 mm along its axis and, in one variant,
  // its elbows 4 times wrong while clearing one bin (docs/experiments.md).
  const bool as_seen = camera_bin.allFinite() && lm.slides.empty();
  const bool facing_only = cfg.refine_facing_only && as_seen;
  const bool by_rays = cfg.refine_ray_pairs && as_seen && lm.sample_directions.size() == lm.samples.size();
  const float radius = 0.5f * lm.tube_d_mm;
  res.pose = start;
  const float inlier = float(cfg.refine_inlier_mm);
  // Coarse to fine: all but the last kFineIterations use every third point; the last (and the
  // reported inliers and rms) all of them.
  constexpr int kFineIterations = 3, kCoarseStride = 3, kRayIterations = 6;
  const int fine_from = std::max(0, cfg.refine_iterations - kFineIterations);
  for (int it = 0; it < cfg.refine_iterations; ++it) {
    const int stride = it < fine_from ? kCoarseStride : 1;
    // Along the rays in the last kRayIterations only: the iterations before, paired with the
    // nearest samples, bring the pose near for less (every iteration along the rays cost the dev
    // set's cycle 1.3x; docs/experiments.md, "The rays' pairing made cheaper").
    const bool rays_now = by_rays && it >= cfg.refine_iterations - kRayIterations;
    const Eigen::Matrix3f r = res.pose.linear().cast<float>();
    const Eigen::Vector3f t = res.pose.translation().cast<float>();
    const Eigen::Matrix3f rt = r.transpose();
    const Eigen::Vector3f c = r * lm.centroid + t;  // linearise about the model's centroid
    const Eigen::Vector3f camera_model = rt * (camera_bin - t);
    Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
    int inliers = 0;
    double sq = 0;
    // Look-ups first, a batch at a time, then the sums: the batch's cache misses overlap instead
    // of each waiting for the last.
    constexpr int kBatch = 16;
    Eigen::Vector3f batch_q[kBatch];
    const LocatorModel::Sample* batch_s[kBatch];
    Eigen::Vector3f batch_dir[kBatch];
    for (int i0 = 0; i0 < n; i0 += stride * kBatch) {
      const int in_batch = std::min(kBatch, (n - i0 + stride - 1) / stride);
      for (int k = 0; k < in_batch; ++k) {
        batch_q[k] = rt * (obs[i0 + k * stride] - t);  // observed point in the model frame
        batch_s[k] = lm.nearest_sample(batch_q[k]);
        if (rays_now && batch_s[k])
          batch_dir[k] = lm.sample_directions[std::size_t(batch_s[k] - lm.samples.data())];
      }
      for (int k = 0; k < in_batch; ++k) {
        const Eigen::Vector3f& q = batch_q[k];
        const LocatorModel::Sample* s = batch_s[k];
        if (!s) continue;
        if ((q - s->p).squaredNorm() > inlier * inlier) continue;
        // The partner: where the camera's ray through q meets the tube round the sample, else the
        // sample.
        Eigen::Vector3f partner = s->p, normal = s->n;
        bool on_ray = false;
        if (rays_now)
          on_ray = ray_meets_tube(camera_model, q, *s, batch_dir[k], radius, inlier, &partner, &normal);
        const Eigen::Vector3f diff = q - partner;
        const Eigen::Vector3f nw = r * normal;
        const Eigen::Vector3f pw = r * partner + t;  // the model point in the bin frame
        if (facing_only && !on_ray) {  // n . v < -slack |v|, v from the sample to the camera, without a root
          const Eigen::Vector3f v = camera_bin - pw;
          const float nv = nw.dot(v);
          if (nv < 0 && nv * nv > kFacingSlack * kFacingSlack * v.squaredNorm()) continue;
        }
        const Eigen::Vector3f mw = pw - c;
        const float res_i = nw.dot(r * diff);  // observed minus model, along the normal
        // Moving the model by (w, v) changes the model point by w x m + v.
        Eigen::Matrix<double, 6, 1> j;
        j.head<3>() = mw.cross(nw).cast<double>();
        j.tail<3>() = nw.cast<double>();
        const double w = std::abs(res_i) < kHuberMm ? 1.0 : double(kHuberMm) / std::abs(res_i);
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
    if (!slides) a.diagonal() *= 1.0 + kDamping;
    res.inliers = inliers * stride;  // about: only the fine iterations count them all
    res.rms_mm = inliers ? float(std::sqrt(sq / inliers)) : 0.f;
    if (inliers < kMinInliers) break;
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
