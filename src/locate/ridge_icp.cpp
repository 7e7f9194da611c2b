#include "locate/ridge_icp.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "locate/rigid_fit.hpp"

namespace pipeloc {
namespace {

// Fewer pairs than this do not hold a rigid fit (six unknowns) against the noise: the run stops.
constexpr int kMinPairs = 6;
// Per iteration the correspondence gate shrinks by this factor, down to D/2: wide enough at
// first to pull a far start in, then only the pipe's own ridge.
constexpr float kGateShrink = 0.7f;

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

}  // namespace

int posed_model_ridge(const LocatorModel& lm, const Pose& pose, const Eigen::Vector2f& axis, float cell_mm,
                      const LocateConfig& cfg, RidgeBuffers* rb, Eigen::Vector3f* out, int capacity) {
  PosedPoints samples;
  samples.points = lm.ridge_samples.data();
  samples.normals = lm.ridge_normals.data();
  samples.count = int(lm.ridge_samples.size());
  samples.stride = ridge_sample_stride(cell_mm, cfg);
  samples.columns = lm.ridge_columns_for(samples.stride);
  samples.to_bin = pose;
  return extract_zridge(samples, axis, cell_mm, kRidgeMinRunOfD * lm.tube_d_mm, rb, out, capacity,
                        cfg.match_surface);
}

void RidgeIcp::reserve(const LocatorModel& lm, const LocateConfig& cfg, int max_ridge_points) {
  lm_ = &lm;
  cfg_ = &cfg;
  model_ridge_.assign(std::size_t(max_ridge_points), Eigen::Vector3f::Zero());
  src_.assign(std::size_t(2 * max_ridge_points), Eigen::Vector3f::Zero());
  dst_.assign(std::size_t(2 * max_ridge_points), Eigen::Vector3f::Zero());
  observed_columns_.reserve(max_ridge_points);
  for (auto* to : {&model_to_, &observed_to_}) to->assign(std::size_t(max_ridge_points), -1);
  for (auto* d2 : {&model_d2_, &observed_d2_}) d2->assign(std::size_t(max_ridge_points), 0.0f);
  reserve_ridge(&ridge_, lm.extent_l_mm + 2 * lm.tube_d_mm, float(cfg.ridge_cell_mm),
                int(lm.ridge_samples.size()));
}

int RidgeIcp::place_model_ridge(const Pose& pose, const Eigen::Vector2f& axis, float cell_mm) {
  return posed_model_ridge(*lm_, pose, axis, cell_mm, *cfg_, &ridge_, model_ridge_.data(),
                           int(model_ridge_.size()));
}

// Nearest partners within radius_mm both ways between the model's ridge (model_ridge_[0..nm)) and
// the observed one, laid out in observed_columns_: model_to_/model_d2_ and observed_to_/observed_d2_
// (-1 where none lies within it). Only partners within the gate or cap count, so that is the radius.
void RidgeIcp::pair_up(int nm, float radius_mm) {
  observed_columns_.nearest_both_ways_within(model_ridge_.data(), nm, radius_mm, model_to_.data(),
                                             model_d2_.data(), observed_to_.data(), observed_d2_.data());
}

// The iterations on the observed ridge, laid out in observed_columns_.
RidgeFit RidgeIcp::iterate(const IcpStart& start, const RidgeView& observed, int max_iterations) {
  const LocatorModel& lm = *lm_;
  const Eigen::Vector3f* obs = observed.points;
  const int n_obs = observed.count;
  RidgeFit fit;
  fit.pose = start.pose;
  const float d = lm.tube_d_mm;
  // Correspondences farther than this are dropped; it shrinks from a third of the pipe to D/2.
  float gate = start.gate_mm > 0 ? start.gate_mm : std::max(lm.extent_l_mm / 3, d);
  for (int it = 0; it < max_iterations; ++it) {
    fit.iterations = it + 1;
    int nm = 0;  // 2.2.1
    if (it == 0 && start.model_ridge) {
      const Eigen::Matrix3f r = fit.pose.linear().cast<float>();
      const Eigen::Vector3f t = fit.pose.translation().cast<float>();
      nm = std::min(start.model_ridge_count, int(model_ridge_.size()));
      for (int i = 0; i < nm; ++i) model_ridge_[std::size_t(i)] = r * start.model_ridge[i] + t;
    } else {
      nm = place_model_ridge(fit.pose, observed.axis, observed.cell_mm);
    }
    pair_up(nm, gate);
    int pairs = 0;
    for (int i = 0; i < nm; ++i) {  // 2.2.2
      const int j = model_to_[std::size_t(i)];
      if (j < 0 || model_d2_[std::size_t(i)] > gate * gate) continue;
      src_[std::size_t(pairs)] = model_ridge_[std::size_t(i)];
      dst_[std::size_t(pairs)] = obs[j];
      ++pairs;
    }
    // Both ways: observed ridge points pull too, so the model cannot slide along the ridge
    // towards parts that were not observed.
    for (int j = 0; j < n_obs && pairs < int(src_.size()); ++j) {
      const int i = observed_to_[std::size_t(j)];
      if (i < 0 || observed_d2_[std::size_t(j)] > gate * gate) continue;
      src_[std::size_t(pairs)] = model_ridge_[std::size_t(i)];
      dst_[std::size_t(pairs)] = obs[j];
      ++pairs;
    }
    if (pairs < kMinPairs) break;
    const Pose delta = fit_rigid(src_.data(), dst_.data(), pairs, lm.straight);  // 2.2.3
    fit.pose = delta * fit.pose;
    gate = std::max(0.5f * d, gate * kGateShrink);
    const double moved =
        delta.translation().norm() + Eigen::AngleAxisd(delta.linear()).angle() * lm.extent_l_mm / 2;
    if (moved < cfg_->icp_converged_mm && gate <= 0.5f * d) break;
  }
  fit.gate_mm = gate;
  return fit;
}

// The closing evaluation of fit->pose: cost_mm, matched, model_ridge_points (the model's ridge
// stays in model_ridge_).
void RidgeIcp::score(const RidgeView& observed, RidgeFit* fit) {
  const int nm = place_model_ridge(fit->pose, observed.axis, observed.cell_mm);
  fit->model_ridge_points = nm;
  const float cap = 0.5f * lm_->tube_d_mm;
  pair_up(nm, cap);
  const float m2o = truncated_mean(model_d2_.data(), nm, cap, &fit->matched);
  const float o2m = truncated_mean(observed_d2_.data(), observed.count, cap, nullptr);
  fit->cost_mm = 0.5f * (m2o + o2m);
}

RidgeFit RidgeIcp::steps(const IcpStart& start, const RidgeView& observed, int max_iterations) {
  RidgeFit unfit;
  unfit.pose = start.pose;
  if (!observed_columns_.assign(observed.points, observed.count)) return unfit;
  return iterate(start, observed, max_iterations);
}

RidgeFit RidgeIcp::fit(const IcpStart& start, const RidgeView& observed, int max_iterations) {
  RidgeFit fit = steps(start, observed, max_iterations);
  // The steps laid out the observed ridge, which the evaluation pairs with again; a ridge larger
  // than the columns were reserved for was not laid out (their count is then below its count): no fit.
  if (observed_columns_.n == observed.count) score(observed, &fit);
  return fit;
}

}  // namespace pipeloc
