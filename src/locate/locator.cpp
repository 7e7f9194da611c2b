#include "locate/locator.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

// IV-B: the frame of the observed axis: X along the measured principal direction, the measured
// centre at the origin. The initial states are placed by it.
Pose axis_frame(const AxisEstimate& est) {
  Pose place = Pose::Identity();
  place.linear() =
      Eigen::AngleAxisd(std::atan2(est.axis.y(), est.axis.x()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  place.translation() = est.centre.cast<double>();
  return place;
}

}  // namespace

const char* outcome_name(CandidateOutcome o) {
  switch (o) {
    case CandidateOutcome::accepted:
      return "accepted";
    case CandidateOutcome::few_ridge_points:
      return "few_ridge_points";
    case CandidateOutcome::residual_too_high:
      return "residual_too_high";
    case CandidateOutcome::not_confirmed:
      return "not_confirmed";
    case CandidateOutcome::duplicate:
      return "duplicate";
    case CandidateOutcome::budget:
      return "budget";
  }
  return "?";
}

Locator::Locator(const PipeModel& model, const LocateConfig& cfg, const Intrinsics& camera)
    : model_(model),
      cfg_(cfg),
      workers_(std::size_t(std::max(1, cfg.threads))),
      pool_(std::max(1, cfg.threads)) {
  lm_ = prepare_locator_model(model, float(cfg.refine_inlier_mm) + 4.0f, cfg);
  starts_ = prepare_starts(lm_, cfg);
  reserve_zbuffer(&zb_, cfg.zbuffer_max_side_mm, cfg.zbuffer_pixel_mm);
  camera_width_ = camera.width, camera_height_ = camera.height;
  reserve_zbuffer_points(&zb_points_, camera.width, camera.height, pool_.size());
  reserve_normals(&nm_, zb_, pool_.size());
  holes_.reserve(zb_);
  band_holes_.assign(std::size_t(pool_.size()), 0);
  reserve_regions(&rb_, zb_, cfg, lm_.tube_d_mm, lm_.extent_l_mm);

  // A ridge point per ridge cell along the pipe, for a pipe folded onto itself twice.
  ridge_capacity_ = int(3 * (lm_.extent_l_mm + 2 * lm_.tube_d_mm) / cfg.ridge_cell_mm) + 16;
  if (cfg.match_surface)  // every ridge cell of the region, not one per line
    ridge_capacity_ = int(rb_.max_region_cells * cfg.zbuffer_pixel_mm * cfg.zbuffer_pixel_mm /
                          (cfg.ridge_cell_mm * cfg.ridge_cell_mm)) +
                      16;
  for (Worker& wk : workers_) {
    reserve_axis(&wk.ab, rb_.max_region_cells, zb_.z.width, zb_.z.height);
    reserve_icp(&wk.icp, lm_, ridge_capacity_, float(cfg.ridge_cell_mm), rb_.max_region_cells);
    wk.region_pts.assign(std::size_t(rb_.max_region_cells), Eigen::Vector3f::Zero());
    wk.coarse_ridge.assign(std::size_t(ridge_capacity_), Eigen::Vector3f::Zero());
    wk.coarse_in_axis.assign(std::size_t(ridge_capacity_), Eigen::Vector3f::Zero());
    wk.fits.reserve(std::size_t(starts_.size()));
    wk.starts.reserve(wk.fits.capacity());
    wk.scratch_depth.resize(camera.width, camera.height, 0.0f);
    wk.scratch_mesh.reserve(lm_.verify_mesh);
  }
  ridge_pts_.assign(std::size_t(ridge_capacity_) * cfg.max_candidates, Eigen::Vector3f::Zero());
  slot_.resize(std::size_t(cfg.max_candidates));
  slot_filled_.assign(std::size_t(cfg.max_candidates), 0);
  out_.estimates.reserve(std::size_t(cfg.max_candidates));
  out_.traces.reserve(std::size_t(cfg.max_candidates));
}

const LocateOutput& Locator::locate(const Image<float>& depth, const CameraInfo& camera,
                                    Clock::time_point deadline) {
  const auto t_start = Clock::now();
  out_.estimates.clear();
  out_.traces.clear();
  out_.times = {};
  out_.budget_exhausted = false;
  out_.regions = {};
  const Pose bin_to_cam = bin_to_camera(camera);
  // Anytime: what is not expected to finish before the deadline is not started. The expected
  // durations are running averages of earlier cycles (none yet: everything is tried).
  if (deadline != Clock::time_point::max() && t_start + ms_duration(serial_ms_avg_) > deadline) {
    out_.budget_exhausted = true;
    out_.times.total_ms = ms_since(t_start);
    return out_;
  }

  auto t = Clock::now();
  build_zbuffer_banded(depth, camera, bin_to_cam);
  out_.times.zbuffer_ms = ms_since(t);

  t = Clock::now();
  const int window = std::max(3, int(std::lround(cfg_.normal_window_mm / zb_.pixel_mm)) | 1);
  // Row bands on the pool: each thread its band, with its own running sums.
  struct NormalTask {
    Locator* self;
    int window, min_valid, bands;
    static void run(void* ctx, int band, int) {
      const NormalTask& t = *static_cast<const NormalTask*>(ctx);
      const ZBuffer& zb = t.self->zb_;
      const int begin = band_begin(band, t.bands, zb.height), end = band_begin(band + 1, t.bands, zb.height);
      compute_normals_rows(zb, t.window, t.min_valid, begin, end, band, &t.self->nm_);
      // II-B's upward cells, while the band's normals are at hand (off the regions' serial path).
      mark_upward_rows(zb, t.self->nm_, t.self->cfg_, begin, end, &t.self->rb_);
    }
  } normal_task{this, window, int(cfg_.normal_min_valid_share * window * window), pool_.size()};
  pool_.run(pool_.size(), &NormalTask::run, &normal_task);
  out_.times.normals_ms = ms_since(t);

  // Candidates are independent: the pool works them, best first, until the deadline. They are
  // taken up as the regions stage hands them out, so that the other threads work candidates
  // while one still grows regions.
  out_.traces.assign(std::size_t(cfg_.max_candidates), CandidateTrace{});
  std::fill(slot_filled_.begin(), slot_filled_.end(), 0);
  for (Worker& wk : workers_) wk.times = {};
  const Clock::time_point start_by =
      deadline == Clock::time_point::max() ? deadline : deadline - ms_duration(candidate_ms_avg_);
  Frame frame{this, &depth, &camera, bin_to_cam, start_by, deadline};
  for (Worker& wk : workers_) wk.candidates_done = 0, wk.candidate_ms_sum = 0;
  Handout handout;
  handout.frame = &frame;
  handout.t_start = t_start;
  pool_.run(pool_.size(), &Locator::regions_and_candidates_task, &handout);
  const int n = int(rb_.candidates.size());
  out_.traces.resize(std::size_t(n));
  constexpr double kAverageWeight = 0.2;
  serial_ms_avg_ = serial_ms_avg_ == 0
                       ? handout.serial_ms
                       : (1 - kAverageWeight) * serial_ms_avg_ + kAverageWeight * handout.serial_ms;
  int done = 0;
  double done_ms = 0;
  for (const Worker& wk : workers_) done += wk.candidates_done, done_ms += wk.candidate_ms_sum;
  if (done > 0)
    candidate_ms_avg_ = candidate_ms_avg_ == 0
                            ? done_ms / done
                            : (1 - kAverageWeight) * candidate_ms_avg_ + kAverageWeight * done_ms / done;
  for (const Worker& wk : workers_) {
    out_.times.axis_ms += wk.times.axis_ms;
    out_.times.ridge_icp_ms += wk.times.ridge_icp_ms;
    out_.times.refine_ms += wk.times.refine_ms;
    out_.times.verify_ms += wk.times.verify_ms;
  }
  for (int c = 0; c < n; ++c) {
    if (out_.traces[std::size_t(c)].outcome == CandidateOutcome::budget) out_.budget_exhausted = true;
    if (slot_filled_[std::size_t(c)]) merge_estimate(c);
  }

  // 7. Rank: best score first; the first pickable one is the pick handed to the PLC.
  // Ties keep candidate order; std::sort with that tie-break, since stable_sort allocates.
  std::sort(out_.estimates.begin(), out_.estimates.end(), [](const PipeEstimate& a, const PipeEstimate& b) {
    return a.score != b.score ? a.score > b.score : a.candidate < b.candidate;
  });
  if (int(out_.estimates.size()) > cfg_.max_results) out_.estimates.resize(std::size_t(cfg_.max_results));
  out_.times.total_ms = ms_since(t_start);
  return out_;
}

void Locator::regions_and_candidates_task(void* ctx, int task, int worker) {
  Handout& h = *static_cast<Handout*>(ctx);
  Locator& self = *h.frame->self;
  if (task == 0) {  // II-B: this thread grows the regions, handing each out as it is found
    const auto t = Clock::now();
    self.out_.regions = extract_candidate_regions(
        self.zb_, self.nm_, self.cfg_, self.lm_.tube_d_mm, self.lm_.extent_l_mm, &self.rb_,
        [](void* c, int found) {
          Handout& hh = *static_cast<Handout*>(c);
          {
            std::lock_guard<std::mutex> lock(hh.mutex);
            hh.found = found;
          }
          hh.more.notify_all();
        },
        &h);
    self.out_.times.regions_ms = ms_since(t);
    h.serial_ms = ms_since(h.t_start);
    {
      std::lock_guard<std::mutex> lock(h.mutex);
      h.regions_done = true;
    }
    h.more.notify_all();
  }
  for (;;) {  // then every thread takes up the next candidate handed out
    int c;
    {
      std::unique_lock<std::mutex> lock(h.mutex);
      h.more.wait(lock, [&] { return h.next < h.found || h.regions_done; });
      if (h.next >= h.found) return;
      c = h.next++;
    }
    candidate_task(h.frame, c, worker);
  }
}

// II-A on the pool: each step of the Z-buffer and of the hole filling in row bands, one per thread.
void Locator::build_zbuffer_banded(const Image<float>& depth, const CameraInfo& camera,
                                   const Pose& bin_to_cam) {
  out_.valid_pixels = 0;
  zb_.width = zb_.height = 0;
  // The buffers were sized for the camera given at construction; callers check frame sizes first.
  if (depth.width != camera_width_ || depth.height != camera_height_) return;
  struct Bands {
    Locator* self;
    const Image<float>* depth;
    const Intrinsics* k;
    const Pose* bin_to_cam;
    int bands;
    float max_spread_mm;
    std::atomic<int> filled{0};
    int lo(int band, int rows) const { return band_begin(band, bands, rows); }
    int hi(int band, int rows) const { return band_begin(band + 1, bands, rows); }
    static void points(void* ctx, int band, int) {
      Bands& b = *static_cast<Bands*>(ctx);
      zbuffer_points_rows(*b.depth, *b.k, *b.bin_to_cam, b.self->zb_.pixel_mm, b.lo(band, b.depth->height),
                          b.hi(band, b.depth->height), band, &b.self->zb_points_, b.self->cfg_.roi);
    }
    static void splat(void* ctx, int band, int) {
      Bands& b = *static_cast<Bands*>(ctx);
      ZBuffer& zb = b.self->zb_;
      splat_zbuffer_rows(b.self->zb_points_, b.lo(band, zb.height), b.hi(band, zb.height), &zb);
    }
    static void collect(void* ctx, int band, int) {
      Bands& b = *static_cast<Bands*>(ctx);
      const ZBuffer& zb = b.self->zb_;
      b.self->band_holes_[std::size_t(band)] =
          collect_holes_rows(zb, b.lo(band, zb.height), b.hi(band, zb.height), &b.self->holes_);
    }
    static void fill(void* ctx, int band, int) {
      Bands& b = *static_cast<Bands*>(ctx);
      const ZBuffer& zb = b.self->zb_;
      b.filled += fill_holes_pass(zb, b.max_spread_mm, b.lo(band, zb.height),
                                  b.self->band_holes_[std::size_t(band)], &b.self->holes_);
    }
    static void apply(void* ctx, int band, int) {
      Bands& b = *static_cast<Bands*>(ctx);
      ZBuffer& zb = b.self->zb_;
      int& count = b.self->band_holes_[std::size_t(band)];
      count = apply_filled(b.lo(band, zb.height), count, &b.self->holes_, &zb);
    }
  } bands{this, &depth, &camera.intrinsics, &bin_to_cam, pool_.size(), float(cfg_.continuity_step_max_mm)};
  pool_.run(bands.bands, &Bands::points, &bands);
  out_.valid_pixels = place_zbuffer(zb_points_, bands.bands, &zb_);
  if (out_.valid_pixels == 0) return;
  pool_.run(bands.bands, &Bands::splat, &bands);
  // Holes of up to hole_fill_mm are filled from both sides: half of it in passes of one cell.
  const int passes = int(std::lround(cfg_.hole_fill_mm / 2 / zb_.pixel_mm));
  if (passes > 0) pool_.run(bands.bands, &Bands::collect, &bands);
  for (int pass = 0; pass < passes; ++pass) {
    bands.filled = 0;
    pool_.run(bands.bands, &Bands::fill, &bands);
    if (bands.filled == 0) break;
    pool_.run(bands.bands, &Bands::apply, &bands);
  }
}

void Locator::candidate_task(void* frame, int c, int worker) {
  const Frame& f = *static_cast<const Frame*>(frame);
  // f.deadline is the real one less an average candidate: a candidate is only begun if it is
  // expected to end in time (the trace stays "budget" otherwise).
  if (f.self->out_of_time(f.deadline)) return;
  Worker& wk = f.self->workers_[std::size_t(worker)];
  const auto t0 = Clock::now();
  f.self->work_candidate(c, wk, *f.depth, *f.camera, f.bin_to_cam, f.deadline_hard);
  ++wk.candidates_done;
  wk.candidate_ms_sum += ms_since(t0);
}

void Locator::merge_estimate(int c) {
  PipeEstimate& e = slot_[std::size_t(c)];
  CandidateTrace& trace = out_.traces[std::size_t(c)];
  // Two regions of one pipe give one estimate: keep the better.
  for (auto& other : out_.estimates) {
    const float same_pipe_mm = 2 * lm_.tube_d_mm;
    if (pose_distance_mm(lm_, other.model_to_bin, e.model_to_bin, same_pipe_mm) > same_pipe_mm) continue;
    if (other.check.agreement() >= e.check.agreement()) {
      trace.outcome = CandidateOutcome::duplicate;
      return;
    }
    out_.traces[std::size_t(other.candidate)].outcome = CandidateOutcome::duplicate;
    other = e;
    return;
  }
  out_.estimates.push_back(e);
}

void Locator::work_candidate(int c, Worker& wk, const Image<float>& depth, const CameraInfo& camera,
                             const Pose& bin_to_cam, Clock::time_point deadline) {
  const CandidateRegion& region = rb_.candidates[std::size_t(c)];
  CandidateTrace& trace = out_.traces[std::size_t(c)];
  const int* cells = &rb_.region_cells[std::size_t(region.cells_begin)];
  const int count = region.cells_end - region.cells_begin;
  const int w = zb_.z.width;
  const float d = lm_.tube_d_mm;

  // III: principal direction and initial position.
  auto t = Clock::now();
  trace.axis = estimate_axis(zb_, cells, count, region.core_centroid, cfg_, d, &wk.ab);
  wk.times.axis_ms += ms_since(t);
  // The budget is checked between steps: a candidate cut short leaves no estimate ("budget").
  if (out_of_time(deadline)) return;

  // IV-A: observed Z-ridge of the region.
  t = Clock::now();
  for (int k = 0; k < count; ++k) wk.region_pts[std::size_t(k)] = zb_.point(cells[k] % w, cells[k] / w);
  Eigen::Vector3f* ridge = &ridge_pts_[std::size_t(c) * ridge_capacity_];
  trace.ridge_begin = c * ridge_capacity_;
  trace.ridge_count = extract_zridge(wk.region_pts.data(), count, trace.axis.axis, float(cfg_.ridge_cell_mm),
                                     0.3f * d, &wk.icp.ridge, ridge, ridge_capacity_, cfg_.match_surface);
  if (trace.ridge_count < 10) {
    trace.outcome = CandidateOutcome::few_ridge_points;
    wk.times.ridge_icp_ms += ms_since(t);
    return;
  }

  // IV-B, Algorithm 2: ICP from the initial states; keep the least residual.
  wk.fits.clear();
  // The probes rank the starts on coarser ridges of the same region.
  const float probe_cell = starts_.cell_mm;
  const int n_coarse =
      extract_zridge(wk.region_pts.data(), count, trace.axis.axis, probe_cell, 0.3f * d, &wk.icp.ridge,
                     wk.coarse_ridge.data(), ridge_capacity_, cfg_.match_surface);
  // Every start is slid to where it best covers the observed ridge ...
  const Pose axis_to_bin = axis_frame(trace.axis);
  const Pose bin_to_axis = axis_to_bin.inverse();
  for (int k = 0; k < n_coarse; ++k)
    wk.coarse_in_axis[std::size_t(k)] =
        (bin_to_axis * wk.coarse_ridge[std::size_t(k)].cast<double>()).cast<float>();
  wk.icp.observed_top.build(wk.coarse_ridge.data(), n_coarse, probe_cell, d);
  wk.starts.clear();
  for (int s = 0; s < starts_.size(); ++s)
    wk.starts.push_back(
        slide_start(lm_, starts_, s, axis_to_bin, wk.coarse_in_axis.data(), n_coarse, cfg_, &wk.icp));
  // ... and those whose ridge covers it best are probed; the most promising continue to convergence.
  std::sort(wk.starts.begin(), wk.starts.end(),
            [](const SlidStart& a, const SlidStart& b) { return a.cost_mm < b.cost_mm; });
  if (int(wk.starts.size()) > cfg_.icp_probed_states) wk.starts.resize(std::size_t(cfg_.icp_probed_states));
  for (const SlidStart& st : wk.starts) {
    // A slow configuration probes long: the deadline (or a shutdown) is checked per start.
    if (out_of_time(deadline)) {
      wk.times.ridge_icp_ms += ms_since(t);
      return;
    }
    wk.fits.push_back(ridge_icp(lm_, st.pose, wk.coarse_ridge.data(), n_coarse, trace.axis.axis, cfg_,
                                cfg_.icp_probe_iterations, &wk.icp, -1, probe_cell, starts_.ridge(st.start),
                                starts_.ridge_count(st.start)));
    wk.fits.back().seen_through = seen_through(wk.fits.back(), wk);
  }
  const auto by_rank = [d](const RidgeFit& x, const RidgeFit& y) { return x.rank_cost(d) < y.rank_cost(d); };
  std::sort(wk.fits.begin(), wk.fits.end(), by_rank);
  // Several starts fall into the same basin: the states continued are distinct ones (more than
  // a diameter apart), so that a runner-up basin, the right one as often as not, is not crowded out.
  int distinct = 0;
  for (std::size_t i = 0; i < wk.fits.size(); ++i) {
    bool seen = false;
    for (int j = 0; j < distinct && !seen; ++j)
      seen = pose_distance_mm(lm_, wk.fits[i].pose, wk.fits[std::size_t(j)].pose, d) < d;
    if (!seen)
      std::rotate(wk.fits.begin() + distinct, wk.fits.begin() + long(i), wk.fits.begin() + long(i) + 1),
          ++distinct;
  }
  const int keep = std::min(int(wk.fits.size()), cfg_.icp_continued_states);
  for (int i = 0; i < keep; ++i) {
    if (out_of_time(deadline)) {
      wk.times.ridge_icp_ms += ms_since(t);
      return;
    }
    RidgeFit& f = wk.fits[std::size_t(i)];
    // Continued on the coarse ridges, then the last icp_fine_iterations on the fine ones.
    const int left = std::max(1, cfg_.icp_max_iterations - f.iterations);
    const int fine = std::min(left, cfg_.icp_fine_iterations);
    if (left > fine)  // (not evaluated: the fine iterations go on from its pose at once)
      f = ridge_icp_steps(lm_, f.pose, wk.coarse_ridge.data(), n_coarse, trace.axis.axis, cfg_, left - fine,
                          &wk.icp, f.gate_mm, probe_cell);
    f = ridge_icp(lm_, f.pose, ridge, trace.ridge_count, trace.axis.axis, cfg_, fine, &wk.icp, f.gate_mm);
    f.seen_through = seen_through(f, wk);
  }
  wk.fits.resize(std::size_t(keep));
  if (out_of_time(deadline)) {
    wk.times.ridge_icp_ms += ms_since(t);
    return;
  }
  // The refinement needs far fewer points than the region holds: keep an even subset.
  const int stride = std::max(1, count / cfg_.refine_max_points);
  int refine_count = 0;
  for (int k = 0; k < count; k += stride)
    wk.region_pts[std::size_t(refine_count++)] = wk.region_pts[std::size_t(k)];
  std::sort(wk.fits.begin(), wk.fits.end(), by_rank);
  wk.times.ridge_icp_ms += ms_since(t);
  trace.ridge_pose = wk.fits[0].pose;
  trace.ridge_cost_mm = wk.fits[0].cost_mm;
  const float r_th = float(cfg_.residual_max_of_d) * d;
  if (std::none_of(wk.fits.begin(), wk.fits.end(), [r_th](const RidgeFit& f) { return f.cost_mm <= r_th; })) {
    trace.outcome = CandidateOutcome::residual_too_high;
    return;
  }

  // Beyond the paper: the least ridge residual is not always the right state (ridges of curved
  // pipes fit in more than one way). The best few distinct states under R_th are refined on the
  // whole region, point to plane, and the depth image judges them (no floating, no sinking, no
  // upside-down pipe). A runner-up the image confirms about as well makes the pipe ambiguous.
  const float ambiguity_mm = float(cfg_.ambiguity_pose_mm);
  PipeEstimate best, second;
  bool have_best = false, have_second = false;
  auto quality = [](const Verification& v) { return v.agreement() - 2 * v.free_space(); };
  // Refines a hypothesis on the region, has the image judge it, and keeps the best two that are
  // more than ambiguity_pose_mm apart.
  const auto judge = [&](const Pose& start, float ridge_cost_mm) {
    auto t0 = Clock::now();
    const RefineResult refined = refine_on_surface(lm_, start, wk.region_pts.data(), refine_count, cfg_);
    wk.times.refine_ms += ms_since(t0);
    t0 = Clock::now();
    PipeEstimate e;
    e.model_to_bin = refined.pose;
    e.model_to_cam = bin_to_cam * refined.pose;
    e.check = verify_pose(lm_.verify_mesh, lm_.verify_winding, e.model_to_cam, depth, camera.intrinsics,
                          float(cfg_.verify_tolerance_mm), &wk.scratch_depth, &wk.scratch_mesh);
    wk.times.verify_ms += ms_since(t0);
    e.ridge_cost_mm = ridge_cost_mm;
    e.ridge_points = trace.ridge_count;
    e.refine_inliers = refined.inliers;
    e.refine_points = refine_count;
    e.refine_rms_mm = refined.rms_mm;
    e.candidate = c;
    if (!have_best || quality(e.check) > quality(best.check)) {
      if (have_best && pose_distance_mm(lm_, best.model_to_bin, e.model_to_bin, ambiguity_mm) > ambiguity_mm)
        second = best, have_second = true;
      best = e, have_best = true;
    } else if (!have_second || quality(e.check) > quality(second.check)) {
      if (pose_distance_mm(lm_, best.model_to_bin, e.model_to_bin, ambiguity_mm) > ambiguity_mm)
        second = e, have_second = true;
    }
  };
  int tried = 0;
  for (std::size_t i = 0; i < wk.fits.size() && tried < cfg_.verify_hypotheses; ++i) {
    if (wk.fits[i].cost_mm > r_th) continue;
    bool seen = false;
    for (std::size_t j = 0; j < i && !seen; ++j)
      seen = wk.fits[j].cost_mm <= r_th &&
             pose_distance_mm(lm_, wk.fits[i].pose, wk.fits[j].pose, ambiguity_mm) < ambiguity_mm;
    if (seen) continue;
    if (out_of_time(deadline)) return;  // an unchecked runner-up could hide an ambiguity
    ++tried;
    judge(wk.fits[i].pose, wk.fits[i].cost_mm);
  }
  // Beyond the paper: a near-symmetric part (a half-turn maps most of it onto itself) seen only
  // where the two poses agree fits both equally; the ridge ICP need not have reached the other.
  // The twin of the best hypothesis is judged too, so that the ambiguity is found, or the twin
  // taken when the image prefers it. A twin the runner-up already stands for is not judged again.
  if (have_best) {
    const Pose found = best.model_to_bin;  // judging a twin may replace the best: twins of this one
    const float found_cost_mm = best.ridge_cost_mm;
    for (const Pose& half_turn : model_.near_symmetries) {
      const Pose twin = found * half_turn;
      if (have_second && pose_distance_mm(lm_, twin, second.model_to_bin, ambiguity_mm) <= ambiguity_mm)
        continue;
      if (out_of_time(deadline)) return;
      judge(twin, found_cost_mm);
    }
  }
  PipeEstimate& e = best;
  trace.check = e.check;
  trace.refined_to_cam = e.model_to_cam;
  if (e.check.agreement() < float(cfg_.verify_min_agreement) ||
      e.check.free_space() > float(cfg_.verify_max_free_space)) {
    trace.outcome = CandidateOutcome::not_confirmed;
    return;
  }
  // A rival the image judges about as well makes the pipe ambiguous, whether or not it passes the
  // thresholds itself: the best passing them by a hair and a rival failing them by one are the same.
  const bool ambiguous =
      have_second && quality(second.check) >= quality(best.check) - float(cfg_.ambiguity_quality_margin);
  e.ambiguous = ambiguous;
  e.score = e.check.agreement() * (1.0f - e.check.occluded()) * (ambiguous ? 0.5f : 1.0f);
  e.pickable = !ambiguous && e.check.occluded() <= float(cfg_.verify_max_occluded);
  trace.outcome = CandidateOutcome::accepted;
  slot_[std::size_t(c)] = e;
  slot_filled_[std::size_t(c)] = 1;
}

}  // namespace pipeloc
