#include "locate/locator.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

double ms_since(Locator::Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Locator::Clock::now() - t0).count();
}

// IV-B: an initial state: the model turned about its axis (canonical start k), its measured
// principal direction laid along the observed one in either direction, its measured centre on
// the observed centre.
Pose initial_state(const LocatorModel& lm, const AxisEstimate& est, bool reverse, int k) {
  double yaw = std::atan2(est.axis.y(), est.axis.x());
  if (reverse) yaw += M_PI;
  Pose place = Pose::Identity();
  place.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  place.translation() = est.centre.cast<double>();
  return place * lm.canonical_starts[std::size_t(k)];
}

}  // namespace

const char* outcome_name(CandidateOutcome o) {
  switch (o) {
    case CandidateOutcome::accepted: return "accepted";
    case CandidateOutcome::few_ridge_points: return "few_ridge_points";
    case CandidateOutcome::residual_too_high: return "residual_too_high";
    case CandidateOutcome::not_confirmed: return "not_confirmed";
    case CandidateOutcome::duplicate: return "duplicate";
    case CandidateOutcome::budget: return "budget";
  }
  return "?";
}

Locator::Locator(const PipeModel& model, const LocateConfig& cfg, const Intrinsics& camera)
    : model_(model), cfg_(cfg) {
  lm_ = prepare_locator_model(model, float(cfg.refine_inlier_mm) + 4.0f, cfg);
  reserve_zbuffer(&zb_, cfg.zbuffer_max_side_mm, cfg.zbuffer_pixel_mm);
  reserve_normals(&nm_, zb_);
  hole_scratch_.assign(zb_.z.pixels.size(), 0.0f);
  reserve_regions(&rb_, zb_, cfg, lm_.tube_d_mm, lm_.extent_l_mm);
  ab_.keys.assign(std::size_t(rb_.max_region_cells), 0);
  // A ridge point per ridge cell along the pipe, for a pipe folded onto itself twice.
  ridge_capacity_ = int(3 * (lm_.extent_l_mm + 2 * lm_.tube_d_mm) / cfg.ridge_cell_mm) + 16;
  reserve_icp(&icp_, lm_, ridge_capacity_, float(cfg.ridge_cell_mm));
  ridge_pts_.assign(std::size_t(ridge_capacity_) * cfg.max_candidates, Eigen::Vector3f::Zero());
  region_pts_.assign(std::size_t(rb_.max_region_cells), Eigen::Vector3f::Zero());
  fits_.reserve(std::size_t(2 * std::max(1, cfg.initial_rotations)));
  scratch_depth_.resize(camera.width, camera.height, 0.0f);
  out_.estimates.reserve(std::size_t(cfg.max_candidates));
  out_.traces.reserve(std::size_t(cfg.max_candidates));
}

const LocateOutput& Locator::locate(const Image<float>& depth, const CameraInfo& camera, Clock::time_point deadline) {
  const auto t_start = Clock::now();
  out_.estimates.clear();
  out_.traces.clear();
  out_.times = {};
  out_.budget_exhausted = false;
  out_.regions = {};
  const Pose bin_to_cam = bin_to_camera(camera);

  auto t = Clock::now();
  out_.valid_pixels = build_zbuffer(depth, camera.intrinsics, bin_to_cam, &zb_);
  fill_small_holes(&zb_, int(std::lround(cfg_.hole_fill_mm / 2 / zb_.pixel_mm)), float(cfg_.continuity_step_max_mm),
                   &hole_scratch_);
  out_.times.zbuffer_ms = ms_since(t);

  t = Clock::now();
  const int window = std::max(3, int(std::lround(cfg_.normal_window_mm / zb_.pixel_mm)) | 1);
  compute_normals(zb_, window, int(cfg_.normal_min_valid_share * window * window), &nm_);
  out_.times.normals_ms = ms_since(t);

  t = Clock::now();
  out_.regions = extract_candidate_regions(zb_, nm_, cfg_, lm_.tube_d_mm, lm_.extent_l_mm, &rb_);
  out_.times.regions_ms = ms_since(t);

  for (int c = 0; c < int(rb_.candidates.size()); ++c) {
    out_.traces.emplace_back();
    if (Clock::now() >= deadline) {
      out_.budget_exhausted = true;
      continue;
    }
    work_candidate(c, depth, camera, bin_to_cam);
  }

  // 7. Rank: best score first; the first pickable one is the pick handed to the PLC.
  std::stable_sort(out_.estimates.begin(), out_.estimates.end(),
                   [](const PipeEstimate& a, const PipeEstimate& b) { return a.score > b.score; });
  if (int(out_.estimates.size()) > cfg_.max_results) out_.estimates.resize(std::size_t(cfg_.max_results));
  out_.times.total_ms = ms_since(t_start);
  return out_;
}

void Locator::work_candidate(int c, const Image<float>& depth, const CameraInfo& camera, const Pose& bin_to_cam) {
  const CandidateRegion& region = rb_.candidates[std::size_t(c)];
  CandidateTrace& trace = out_.traces[std::size_t(c)];
  const int* cells = &rb_.region_cells[std::size_t(region.cells_begin)];
  const int count = region.cells_end - region.cells_begin;
  const int w = zb_.z.width;
  const float d = lm_.tube_d_mm;

  // III: principal direction and initial position.
  auto t = Clock::now();
  trace.axis = estimate_axis(zb_, cells, count, region.core_centroid, cfg_, d, &ab_);
  out_.times.axis_ms += ms_since(t);

  // IV-A: observed Z-ridge of the region.
  t = Clock::now();
  for (int k = 0; k < count; ++k) region_pts_[std::size_t(k)] = zb_.point(cells[k] % w, cells[k] / w);
  Eigen::Vector3f* ridge = &ridge_pts_[std::size_t(c) * ridge_capacity_];
  trace.ridge_begin = c * ridge_capacity_;
  trace.ridge_count = extract_zridge(region_pts_.data(), count, trace.axis.axis, float(cfg_.ridge_cell_mm), 0.3f * d,
                                     &icp_.ridge, ridge, ridge_capacity_);
  if (trace.ridge_count < 10) {
    trace.outcome = CandidateOutcome::few_ridge_points;
    out_.times.ridge_icp_ms += ms_since(t);
    return;
  }

  // IV-B, Algorithm 2: ICP from 2 x initial_rotations states; keep the least residual.
  fits_.clear();
  const int turns = std::max(1, cfg_.initial_rotations);
  for (int dir = 0; dir < 2; ++dir)
    for (int r = 0; r < turns; ++r)
      fits_.push_back(ridge_icp(lm_, initial_state(lm_, trace.axis, dir == 1, r), ridge,
                                trace.ridge_count, trace.axis.axis, cfg_, &icp_));
  std::sort(fits_.begin(), fits_.end(), [](const RidgeFit& x, const RidgeFit& y) { return x.cost_mm < y.cost_mm; });
  out_.times.ridge_icp_ms += ms_since(t);
  trace.ridge_pose = fits_[0].pose;
  trace.ridge_cost_mm = fits_[0].cost_mm;
  if (fits_[0].cost_mm > float(cfg_.residual_max_of_d) * d) {
    trace.outcome = CandidateOutcome::residual_too_high;
    return;
  }

  // Beyond the paper: the least ridge residual is not always the right state (ridges of curved
  // pipes fit in more than one way). The best few distinct states under R_th are refined on the
  // whole region, point to plane, and the depth image judges them (no floating, no sinking, no
  // upside-down pipe). A runner-up the image confirms about as well makes the pipe ambiguous.
  PipeEstimate best, second;
  bool have_best = false, have_second = false;
  auto quality = [](const Verification& v) { return v.agreement() - 2 * v.free_space(); };
  int tried = 0;
  for (std::size_t i = 0; i < fits_.size() && tried < cfg_.verify_hypotheses; ++i) {
    if (fits_[i].cost_mm > float(cfg_.residual_max_of_d) * d) break;
    bool seen = false;
    for (std::size_t j = 0; j < i && !seen; ++j)
      seen = fits_[j].cost_mm <= float(cfg_.residual_max_of_d) * d &&
             pose_distance_mm(lm_, fits_[i].pose, fits_[j].pose) < float(cfg_.ambiguity_pose_mm);
    if (seen) continue;
    ++tried;
    t = Clock::now();
    const RefineResult refined = refine_on_surface(lm_, fits_[i].pose, region_pts_.data(), count, cfg_);
    out_.times.refine_ms += ms_since(t);
    t = Clock::now();
    PipeEstimate e;
    e.model_to_bin = refined.pose;
    e.model_to_cam = bin_to_cam * refined.pose;
    e.check = verify_pose(model_.mesh, e.model_to_cam, depth, camera.intrinsics, float(cfg_.verify_tolerance_mm),
                          &scratch_depth_);
    out_.times.verify_ms += ms_since(t);
    e.ridge_cost_mm = fits_[i].cost_mm;
    e.ridge_points = trace.ridge_count;
    e.refine_inliers = refined.inliers;
    e.refine_rms_mm = refined.rms_mm;
    e.candidate = c;
    if (!have_best || quality(e.check) > quality(best.check)) {
      if (have_best && pose_distance_mm(lm_, best.model_to_bin, e.model_to_bin) > float(cfg_.ambiguity_pose_mm))
        second = best, have_second = true;
      best = e, have_best = true;
    } else if (!have_second || quality(e.check) > quality(second.check)) {
      if (pose_distance_mm(lm_, best.model_to_bin, e.model_to_bin) > float(cfg_.ambiguity_pose_mm))
        second = e, have_second = true;
    }
  }
  PipeEstimate& e = best;
  if (e.check.agreement() < float(cfg_.verify_min_agreement) || e.check.free_space() > float(cfg_.verify_max_free_space)) {
    trace.outcome = CandidateOutcome::not_confirmed;
    return;
  }
  const bool ambiguous = have_second && second.check.agreement() >= float(cfg_.verify_min_agreement) &&
                         second.check.free_space() <= float(cfg_.verify_max_free_space) &&
                         quality(second.check) >= quality(best.check) - float(cfg_.ambiguity_quality_margin);
  e.ambiguous = ambiguous;
  e.score = e.check.agreement() * (1.0f - e.check.occluded()) * (ambiguous ? 0.5f : 1.0f);
  e.pickable = !ambiguous && e.check.occluded() <= float(cfg_.verify_max_occluded);
  // Two regions of one pipe give one estimate: keep the better.
  for (auto& other : out_.estimates) {
    if (pose_distance_mm(lm_, other.model_to_bin, e.model_to_bin) > 2 * d) continue;
    if (other.check.agreement() >= e.check.agreement()) {
      trace.outcome = CandidateOutcome::duplicate;
      return;
    }
    out_.traces[std::size_t(other.candidate)].outcome = CandidateOutcome::duplicate;
    other = e;
    trace.outcome = CandidateOutcome::accepted;
    return;
  }
  trace.outcome = CandidateOutcome::accepted;
  out_.estimates.push_back(e);
}

}  // namespace pipeloc
