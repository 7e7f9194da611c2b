#include "locate/locator.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {
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
  for (Worker& wk : workers_)
    reserve_candidate(&wk.buf, lm_, starts_, cfg, rb_.max_region_cells, ridge_capacity_, zb_.z.width, zb_.z.height,
                      camera);
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
  for (Worker& wk : workers_) wk.buf.times = {};
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
    out_.times.axis_ms += wk.buf.times.axis_ms;
    out_.times.ridge_icp_ms += wk.buf.times.ridge_icp_ms;
    out_.times.refine_ms += wk.buf.times.refine_ms;
    out_.times.verify_ms += wk.buf.times.verify_ms;
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
                          b.hi(band, b.depth->height), band, &b.self->zb_points_);
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
  f.self->work_candidate(c, wk, f);
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

void Locator::work_candidate(int c, Worker& wk, const Frame& f) {
  const CandidateContext ctx{model_, lm_, starts_, cfg_, zb_, *f.depth, f.camera->intrinsics, f.bin_to_cam};
  CandidateInput in;
  in.index = c;
  in.region = &rb_.candidates[std::size_t(c)];
  in.cells = &rb_.region_cells[std::size_t(in.region->cells_begin)];
  in.ridge = &ridge_pts_[std::size_t(c) * ridge_capacity_];
  in.ridge_capacity = ridge_capacity_;
  CandidateTrace& trace = out_.traces[std::size_t(c)];
  trace.ridge_begin = c * ridge_capacity_;
  if (pipeloc::work_candidate(ctx, in, Deadline{f.deadline_hard, cancel_}, &wk.buf, &trace,
                              &slot_[std::size_t(c)]))
    slot_filled_[std::size_t(c)] = 1;
}

}  // namespace pipeloc
