#include "locate/locator.hpp"

#include <algorithm>
#include <cmath>

#include "locate/speckles.hpp"

namespace pipeloc {
namespace {

// The candidate stages of one worker's buffers, summed over the threads.
void add_candidate_times(const CandidateTimes& of, StageTimes* to) {
  to->axis_ms += of.axis_ms;
  to->ridge_icp_ms += of.ridge_icp_ms;
  to->refine_ms += of.refine_ms;
  to->verify_ms += of.verify_ms;
}

}  // namespace

Locator::Locator(const PipeModel& model, const LocateConfig& cfg, const Intrinsics& camera)
    : model_(model),
      user_cfg_(cfg),
      cfg_(with_model_thresholds(cfg, model.tube_diameter_mm)),
      workers_(std::size_t(std::max(1, cfg.threads))),
      pool_(std::max(1, cfg.threads)) {
  lm_ = prepare_locator_model(model, max_refine_inlier_mm(cfg, model.tube_diameter_mm) + 4.0f, cfg);
  starts_ = prepare_starts(lm_, cfg);
  retry_on_surface_ = cfg.retry_surface_cell_of_d > 0 && !cfg.match_surface;
  retry_user_cfg_ = surface_retry_config(user_cfg_, model.tube_diameter_mm);
  retry_cfg_ = surface_retry_config(cfg_, model.tube_diameter_mm);
  if (retry_on_surface_) retry_starts_ = prepare_starts(lm_, retry_user_cfg_);
  reserve_zbuffer(&zb_, cfg.zbuffer_max_side_mm, cfg.zbuffer_pixel_mm);
  camera_width_ = camera.width, camera_height_ = camera.height;
  reserve_zbuffer_points(&zb_points_, camera.width, camera.height, pool_.size());
  if (cfg.remove_speckles) depth_kept_.resize(camera.width, camera.height, 0.0f);
  reserve_normals(&nm_, zb_, pool_.size());
  holes_.reserve(zb_);
  constexpr int kHeightBinsMm = 8192;  // heights over 8 m in one frame are not a bin
  height_histogram_.assign(std::size_t(kHeightBinsMm), 0);
  col_reads_.assign(std::size_t(camera.width), 0);
  row_reads_.assign(std::size_t(camera.height), 0);
  band_holes_.assign(std::size_t(pool_.size()), 0);
  reserve_regions(&rb_, zb_, cfg, lm_.tube_d_mm, lm_.extent_l_mm);

  // A ridge point per ridge cell along the pipe, for a pipe folded onto itself twice.
  ridge_capacity_ = int(3 * (lm_.extent_l_mm + 2 * lm_.tube_d_mm) / cfg.ridge_cell_mm) + 16;
  // Every ridge cell of the region, not one per line (the surface matched, first or again).
  const auto surface_cells = [&](double cell_mm) {
    return int(rb_.max_region_cells * cfg.zbuffer_pixel_mm * cfg.zbuffer_pixel_mm / (cell_mm * cell_mm)) + 16;
  };
  if (cfg.match_surface) ridge_capacity_ = surface_cells(cfg.ridge_cell_mm);
  if (retry_on_surface_)
    ridge_capacity_ = std::max(ridge_capacity_, surface_cells(retry_user_cfg_.ridge_cell_mm));
  // The buffers keep a pointer to the config (RidgeIcp): ours, not the caller's, which may be a
  // temporary (ASan: stack-use-after-scope in RidgeIcp::iterate).
  for (Worker& wk : workers_) {
    reserve_candidate(&wk.buf, lm_, starts_, user_cfg_, rb_.max_region_cells, ridge_capacity_, zb_.z.width,
                      zb_.z.height, camera);
    if (!retry_on_surface_) continue;
    reserve_candidate(&wk.retry_buf, lm_, retry_starts_, retry_user_cfg_, rb_.max_region_cells,
                      ridge_capacity_, zb_.z.width, zb_.z.height, camera);
    wk.retry_ridge.assign(std::size_t(ridge_capacity_), Eigen::Vector3f::Zero());
  }
  ridge_pts_.assign(std::size_t(ridge_capacity_) * cfg.max_candidates, Eigen::Vector3f::Zero());
  slot_.resize(std::size_t(cfg.max_candidates));
  slot_filled_.assign(std::size_t(cfg.max_candidates), 0);
  to_search_again_.assign(std::size_t(cfg.max_candidates), -1);
  explained_.assign(std::size_t(rb_.max_region_cells), 0);
  out_.estimates.reserve(std::size_t(cfg.max_candidates));
  out_.traces.reserve(std::size_t(cfg.max_candidates));
}

const LocateOutput& Locator::locate(const Image<float>& depth_mm, const CameraInfo& camera,
                                    Clock::time_point deadline) {
  locate_to_pick(depth_mm, camera, deadline);
  return search_again();
}

const LocateOutput& Locator::locate_to_pick(const Image<float>& frame_depth, const CameraInfo& camera,
                                            Clock::time_point deadline) {
  const auto t_start = Clock::now();
  frame_start_ = t_start;
  searches_again_ = 0;
  out_.estimates.clear();
  out_.traces.clear();
  out_.times = {};
  out_.budget_exhausted = false;
  out_.regions = {};
  const Pose bin_to_cam = bin_to_camera(camera);
  // The thresholds that follow the sensor: its noise and pixel footprint, measured in this frame
  // (only when a key is left to be derived from it).
  if (derives_from_frame(user_cfg_)) {
    out_.noise = measure_depth_noise(frame_depth, &noise_histograms_);
    set_frame_thresholds(user_cfg_, model_.tube_diameter_mm, out_.noise, camera.intrinsics, &cfg_);
    if (retry_on_surface_) retry_cfg_ = surface_retry_config(cfg_, model_.tube_diameter_mm);
  }
  // Anytime: what is not expected to finish before the deadline is not started. The expected
  // durations are running averages of earlier cycles (none yet: everything is tried).
  if (deadline != Clock::time_point::max() && t_start + ms_duration(serial_ms_avg_) > deadline) {
    out_.budget_exhausted = true;
    out_.times.total_ms = ms_since(t_start);
    return out_;
  }

  auto t = Clock::now();
  out_.speckles = cfg_.remove_speckles
                      ? remove_speckles(frame_depth, float(cfg_.continuity_step_max_mm), &depth_kept_)
                      : 0;
  const Image<float>& depth = cfg_.remove_speckles ? depth_kept_ : frame_depth;
  build_zbuffer_banded(depth, camera, bin_to_cam);
  // The floor: the height only 2 % of the visible surface lies under (noise takes the lowest cells
  // of a seen floor a little deeper, which errs on the side of keeping a pose).
  constexpr float kLowestSurfaceShare = 0.02f;
  out_.lowest_surface_z_mm = lowest_surface_z(zb_, kLowestSurfaceShare, &height_histogram_);
  out_.view = read_view(depth, &col_reads_, &row_reads_);
  out_.times.zbuffer_ms = ms_since(t);

  t = Clock::now();
  const int window = std::max(3, int(std::lround(cfg_.normal_window_mm / zb_.pixel_mm)) | 1);
  // Row bands on the pool: each thread its band, with its own running sums.
  const int min_valid = int(cfg_.normal_min_valid_share * window * window), bands = pool_.size();
  pool_.run(bands, [&](int band, int) {
    const int begin = band_begin(band, bands, zb_.height), end = band_begin(band + 1, bands, zb_.height);
    compute_normals_rows(zb_, window, min_valid, begin, end, band, &nm_);
    // II-B's upward cells, while the band's normals are at hand (off the regions' serial path).
    mark_upward_rows(zb_, nm_, cfg_, begin, end, &rb_);
  });
  out_.times.normals_ms = ms_since(t);

  // Candidates are independent: the pool works them, best first, until the deadline. They are
  // taken up as the regions stage hands them out, so that the other threads work candidates
  // while one still grows regions.
  out_.traces.assign(std::size_t(cfg_.max_candidates), CandidateTrace{});
  std::fill(slot_filled_.begin(), slot_filled_.end(), 0);
  for (Worker& wk : workers_) wk.buf.times = wk.retry_buf.times = {};
  const Clock::time_point start_by =
      deadline == Clock::time_point::max() ? deadline : deadline - ms_duration(candidate_ms_avg_);
  Frame frame{&depth, &camera, bin_to_cam, start_by, deadline};
  for (Worker& wk : workers_) wk.candidates_done = 0, wk.candidate_ms_sum = 0;
  Handout handout;
  handout.frame = &frame;
  handout.t_start = t_start;
  pool_.run(pool_.size(), [&](int task, int worker) { regions_and_candidates(handout, task, worker); });
  first_leftover_ = int(rb_.candidates.size());
  if (cfg_.leftover_regions) leftover_candidates(frame, first_leftover_);
  frame_ = frame;  // for search_again()
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
  for (const Worker& wk : workers_) add_candidate_times(wk.buf.times, &out_.times);
  for (int c = 0; c < n; ++c) {
    if (out_.traces[std::size_t(c)].outcome == CandidateOutcome::budget) out_.budget_exhausted = true;
    if (slot_filled_[std::size_t(c)]) merge_estimate(c);
  }
  if (cfg_.rivals_across_regions) mark_pipes_read_two_ways();
  mark_tried();
  rank();
  // Beyond the paper: where the first searches hand out no pose, the second searches may
  // (second_search_may_pick): they run now, before the result, and their poses are judged with
  // the others' across regions.
  if (cfg_.second_search_may_pick && out_.pick() < 0 && !out_.budget_exhausted && searches_again_ > 0) {
    const bool searched_to_the_end = second_searches(nullptr);
    if (cfg_.rivals_across_regions) {
      mark_pipes_read_two_ways();
      rank();
    }
    // Still no pick, and the deadline ended a second search: the budget ran out before the
    // image was searched (ERROR 3, not DONE_NONE).
    if (out_.pick() < 0 && !searched_to_the_end) out_.budget_exhausted = true;
  }
  out_.times.total_ms = ms_since(t_start);
  return out_;
}

// Beyond the paper: the regions whose ridge fits end in poses the image does not confirm are
// searched again, their whole top surface matched (retry_surface_cell_of_d). A ridge, one point
// per cross-section, places a short pipe or a short piece of one by a few points (an 8.4 mm
// elbow's region: 8-20), and its fits end turned or flipped; the surface holds the region's
// shape. Only for regions the ridge search failed on: for every region, the surface's fits lose
// long pipes (docs/experiments.md). Its poses are reported, and handed out only where the first
// searches hand out none (decide(), LocateOutput::pick()): the second searches come after the
// pick, in the time the frame's deadline leaves, or, where there is no pick, before it.
const LocateOutput& Locator::search_again(const std::atomic<bool>* interrupt) {
  second_searches(interrupt);
  return out_;
}

bool Locator::second_searches(const std::atomic<bool>* interrupt) {
  const int n = searches_again_;
  if (n == 0) return true;
  searches_again_ = 0;  // once per frame
  const auto t = Clock::now();
  const bool to_the_end = search_regions_again(frame_, n, interrupt);
  for (const Worker& wk : workers_) add_candidate_times(wk.retry_buf.times, &out_.times);
  for (int k = 0; k < n; ++k) {  // in the candidates' order, as the first searches were merged
    const int c = to_search_again_[std::size_t(k)];
    if (slot_filled_[std::size_t(c)]) merge_estimate(c);
  }
  mark_tried();
  rank();
  out_.times.again_ms = ms_since(t);
  out_.times.total_ms = ms_since(frame_start_);
  return to_the_end;
}

// 7. Rank: best score first; the first pickable one is the pick handed to the PLC.
// Ties keep candidate order; std::sort with that tie-break, since stable_sort allocates.
void Locator::rank() {
  std::sort(out_.estimates.begin(), out_.estimates.end(), [](const PipeEstimate& a, const PipeEstimate& b) {
    return a.score != b.score ? a.score > b.score : a.candidate < b.candidate;
  });
  if (int(out_.estimates.size()) > cfg_.result_cap()) out_.estimates.resize(std::size_t(cfg_.result_cap()));
}

void Locator::regions_and_candidates(Handout& h, int task, int worker) {
  if (task == 0) {  // II-B: this thread grows the regions, handing each out as it is found
    const auto t = Clock::now();
    out_.regions = extract_candidate_regions(
        zb_, nm_, cfg_, lm_.tube_d_mm, lm_.extent_l_mm, &rb_,
        [](void* c, int found) {
          Handout& hh = *static_cast<Handout*>(c);
          {
            std::lock_guard<std::mutex> lock(hh.mutex);
            hh.found = found;
          }
          hh.more.notify_all();
        },
        &h);
    out_.times.regions_ms = ms_since(t);
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
    candidate_task(*h.frame, c, worker);
  }
}

// II-A on the pool: each step of the Z-buffer and of the hole filling in row bands, one per thread.
void Locator::build_zbuffer_banded(const Image<float>& depth, const CameraInfo& camera,
                                   const Pose& bin_to_cam) {
  out_.valid_pixels = 0;
  zb_.width = zb_.height = 0;
  // The buffers were sized for the camera given at construction; callers check frame sizes first.
  if (depth.width != camera_width_ || depth.height != camera_height_) return;
  const int bands = pool_.size();
  const auto lo = [bands](int band, int rows) { return band_begin(band, bands, rows); };
  const auto hi = [bands](int band, int rows) { return band_begin(band + 1, bands, rows); };
  const Intrinsics& k = camera.intrinsics;
  pool_.run(bands, [&](int band, int) {
    zbuffer_points_rows(depth, k, bin_to_cam, zb_.pixel_mm, lo(band, depth.height), hi(band, depth.height),
                        band, &zb_points_, cfg_.roi);
  });
  out_.valid_pixels = place_zbuffer(zb_points_, bands, &zb_);
  if (out_.valid_pixels == 0) return;
  pool_.run(bands, [&](int band, int) {
    splat_zbuffer_rows(zb_points_, lo(band, zb_.height), hi(band, zb_.height), &zb_);
  });
  // Holes of up to hole_fill_mm are filled from both sides: half of it in passes of one cell.
  const int passes = int(std::lround(cfg_.hole_fill_mm / 2 / zb_.pixel_mm));
  if (passes > 0)
    pool_.run(bands, [&](int band, int) {
      band_holes_[std::size_t(band)] =
          collect_holes_rows(zb_, lo(band, zb_.height), hi(band, zb_.height), &holes_);
    });
  const float max_spread_mm = float(cfg_.continuity_step_max_mm);
  std::atomic<int> filled{0};
  for (int pass = 0; pass < passes; ++pass) {
    filled = 0;
    pool_.run(bands, [&](int band, int) {
      filled +=
          fill_holes_pass(zb_, max_spread_mm, lo(band, zb_.height), band_holes_[std::size_t(band)], &holes_);
    });
    if (filled == 0) break;
    pool_.run(bands, [&](int band, int) {
      int& count = band_holes_[std::size_t(band)];
      count = apply_filled(lo(band, zb_.height), count, &holes_, &zb_);
    });
  }
}

void Locator::candidate_task(const Frame& f, int c, int worker) {
  // f.deadline is the real one less an average candidate: a candidate is only begun if it is
  // expected to end in time (the trace stays "budget" otherwise).
  if (Deadline{f.deadline, cancel_}.passed()) return;
  Worker& wk = workers_[std::size_t(worker)];
  const auto t0 = Clock::now();
  work_candidate(c, wk, f);
  ++wk.candidates_done;
  wk.candidate_ms_sum += ms_since(t0);
}

void Locator::leftover_candidates(const Frame& f, int n) {
  // A cell is explained where it lies within the verification's tolerance of the pose's surface
  // (the voxel index names the nearest surface sample within a voxel's half diagonal).
  const float near_mm = float(cfg_.verify_tolerance_mm) + 0.5f * std::sqrt(3.0f) * LocatorModel::voxel_mm;
  const int w = zb_.z.width;
  for (int c = 0; c < n; ++c) {
    if (!slot_filled_[std::size_t(c)]) continue;
    const CandidateRegion& region = rb_.candidates[std::size_t(c)];
    const Eigen::Isometry3f bin_to_model = slot_[std::size_t(c)].model_to_bin.inverse().cast<float>();
    const int* cells = &rb_.region_cells[std::size_t(region.cells_begin)];
    for (int k = 0; k < region.cells_end - region.cells_begin; ++k) {
      const Eigen::Vector3f p = bin_to_model * zb_.point(cells[k] % w, cells[k] / w);
      const LocatorModel::Sample* s = lm_.nearest_sample(p);
      explained_[std::size_t(k)] = s && (p - s->p).squaredNorm() <= near_mm * near_mm;
    }
    out_.regions.leftover +=
        add_leftover_region(zb_, nm_, cfg_, lm_.tube_d_mm, lm_.extent_l_mm, c, explained_.data(), &rb_) >= 0;
  }
  out_.regions.candidates = int(rb_.candidates.size());
  std::atomic<int> next{n};
  const int end = int(rb_.candidates.size());
  if (end == n) return;
  pool_.run(pool_.size(), [&](int, int worker) {
    for (int c = next++; c < end; c = next++) candidate_task(f, c, worker);
  });
}

void Locator::merge_estimate(int c) {
  PipeEstimate& e = slot_[std::size_t(c)];
  CandidateTrace& trace = out_.traces[std::size_t(c)];
  // Two regions of one pipe give one estimate: keep the better. A leftover region is there for
  // another pipe: what it finds of one already found is dropped (a short leftover of a pipe's own
  // region, its ends less placed, would take a pickable pose's place). Two poses are of one pipe
  // where they lie within 2 D and share kRivalMinSharedTube of the tube, as rival hypotheses do:
  // two pipes side by side, a diameter apart, share none of it (one of them was dropped as the
  // other's duplicate: a top pipe each of 04-elbow and 01-straight of the zoo).
  for (auto& other : out_.estimates) {
    const float same_pipe_mm = kSamePipeOfD * lm_.tube_d_mm;
    if (pose_distance_mm(lm_, other.model_to_bin, e.model_to_bin, same_pipe_mm) > same_pipe_mm) continue;
    if (!share_the_tube(lm_, e.model_to_bin, other.model_to_bin)) continue;
    // A pose of the second search (picked only where the first searches pick none) does not take
    // the place of the first search's, nor keep its own against one: a coil's pickable pose gave
    // way to a second search's agreeing better (17-coil, 3 bins: 59 -> 52 pipes taken).
    const bool again = e.searched_again, other_again = other.searched_again;
    const bool keep_other = again != other_again
                                ? again
                                : (other.check.agreement() >= e.check.agreement() || c >= first_leftover_);
    if (keep_other) {
      trace.outcome = CandidateOutcome::duplicate;
      return;
    }
    out_.traces[std::size_t(other.candidate)].outcome = CandidateOutcome::duplicate;
    other = e;
    return;
  }
  out_.estimates.push_back(e);
}

// Beyond the paper: each candidate judges its own hypotheses' rivals, but two regions of one pipe
// reaching out of the view may each read it another way, both confirmed about as well, neither a
// rival of the other's: what tells them apart may lie out of the view. Such a pair is ambiguous:
// neither is handed out (23-planar of the zoo: a 442 mm J bend 42 % out of the view read 270 mm
// round its bend by one region and right by another, the first handed out while clearing). The
// first searches' estimates, and the second searches' too where those run before the pick
// (second_search_may_pick): after a pick, the second searches' poses are never handed out.
// Wholly in the view, the reading whose ends the image shows worse is no estimate of the pipe
// (reading_its_ends_refute): its region's outcome becomes "duplicate". In or out of the view, a
// reading the image confirms clearly worse than another's of the pipe is ambiguous
// (reading_read_worse).
void Locator::mark_pipes_read_two_ways() {
  auto& es = out_.estimates;
  const auto dropped = [&](const PipeEstimate& e) {
    return out_.traces[std::size_t(e.candidate)].outcome == CandidateOutcome::duplicate;
  };
  const auto mark_read_two_ways = [](PipeEstimate* e) {
    if (!e->ambiguous()) e->score *= kAmbiguousScoreFactor;
    e->ambiguous_why |= kAmbiguousReadTwoWays;
    e->pickable = e->unresolved = false;
    e->withheld |= kWithheldAmbiguous;
  };
  for (std::size_t i = 0; i < es.size(); ++i)
    for (std::size_t j = i + 1; j < es.size() && !dropped(es[i]); ++j) {
      if (dropped(es[j])) continue;
      const int refuted = reading_its_ends_refute(lm_, es[i], es[j], cfg_);
      if (refuted >= 0) {
        out_.traces[std::size_t(es[refuted == 0 ? i : j].candidate)].outcome = CandidateOutcome::duplicate;
        continue;
      }
      const int worse = reading_read_worse(lm_, es[i], es[j], cfg_);
      if (worse >= 0) {
        mark_read_two_ways(&es[worse == 0 ? i : j]);
        continue;
      }
      if (!read_two_ways(lm_, es[i], es[j], cfg_)) continue;
      for (PipeEstimate* e : {&es[i], &es[j]}) mark_read_two_ways(e);
    }
  es.erase(std::remove_if(es.begin(), es.end(), dropped), es.end());
}

void Locator::set_tried(const Pose* model_to_cam, int n) {
  tried_count_ = std::clamp(n, 0, kMaxTried);
  std::copy_n(model_to_cam, tried_count_, tried_);
}

// Beyond the paper: a pose handed out whose pick left the bin unchanged (set_tried) is not handed
// out again while it stays so: a cell whose gripper cannot take a pipe, or whose pose of it is
// wrong, would otherwise be sent to the same place frame after frame. Only the same pick again,
// up to the noise: within kTriedSameOfD D everywhere, for a straight tube on its centreline
// (pick_distance_mm: read turned about its own length on the next frame, its surface up to D
// away, it is the same pick, and compared surface to surface it was handed out again). A bent
// pipe's turn about its length is another pick: compared on the centreline, a 12-Z of the zoo had
// its right reading withheld after a wrong one turned 40 degrees (3 pipes fewer in 6 bins). A
// right pose beside a wrong one just over the scorer's bound stays pickable (within 2 D instead,
// two pipes fewer were taken over 6 bins of 7 shapes; docs/experiments.md, "A pick that took
// nothing").
void Locator::mark_tried() {
  const float same_mm = kTriedSameOfD * lm_.tube_d_mm;
  const auto distance_mm = lm_.straight ? pick_distance_mm : pose_distance_mm;
  for (PipeEstimate& e : out_.estimates)
    for (int k = 0; k < tried_count_; ++k)
      if (distance_mm(lm_, tried_[k], e.model_to_cam, same_mm) <= same_mm) {
        e.pickable = e.unresolved = false;
        e.withheld |= kWithheldTookNothing;
        break;
      }
}

CandidateContext Locator::context(const StartSet& starts, const LocateConfig& cfg, const Frame& f) const {
  return CandidateContext{
      model_,   lm_, starts, cfg, zb_, *f.depth, f.camera->intrinsics, f.bin_to_cam, out_.lowest_surface_z_mm,
      out_.view};
}

CandidateInput Locator::candidate_input(int c) {
  CandidateInput in;
  in.index = c;
  in.region = &rb_.candidates[std::size_t(c)];
  in.cells = &rb_.region_cells[std::size_t(in.region->cells_begin)];
  in.ridge = &ridge_pts_[std::size_t(c) * ridge_capacity_];
  in.ridge_capacity = ridge_capacity_;
  return in;
}

void Locator::work_candidate(int c, Worker& wk, const Frame& f) {
  const CandidateContext ctx = context(starts_, cfg_, f);
  CandidateTrace& trace = out_.traces[std::size_t(c)];
  trace.ridge_begin = c * ridge_capacity_;
  if (pipeloc::work_candidate(ctx, candidate_input(c), Deadline{f.deadline_hard, cancel_}, &wk.buf, &trace,
                              &slot_[std::size_t(c)]))
    slot_filled_[std::size_t(c)] = 1;
  else if (retry_on_surface_ && trace.outcome == CandidateOutcome::not_confirmed)
    to_search_again_[std::size_t(searches_again_++)] = c;
}

bool Locator::search_regions_again(const Frame& f, int n, const std::atomic<bool>* interrupt) {
  std::sort(to_search_again_.begin(), to_search_again_.begin() + n);  // in the candidates' order
  std::atomic<int> next{0}, done{0};
  pool_.run(pool_.size(), [&](int, int worker) {
    for (int k = next++; k < n; k = next++)
      if (!Deadline{f.deadline, cancel_, interrupt}.passed())
        done += search_region_again(to_search_again_[std::size_t(k)], workers_[std::size_t(worker)], f,
                                    interrupt);
  });
  return done == n;
}

bool Locator::search_region_again(int c, Worker& wk, const Frame& f, const std::atomic<bool>* interrupt) {
  const CandidateContext again = context(retry_starts_, retry_cfg_, f);
  CandidateInput surface = candidate_input(c);
  Eigen::Vector3f* const ridge = surface.ridge;
  surface.ridge = wk.retry_ridge.data();  // the first search's ridge stays in the trace's place
  surface.searched_again = true;
  CandidateTrace& trace = out_.traces[std::size_t(c)];
  CandidateTrace retried;
  retried.ridge_begin = trace.ridge_begin;
  retried.searched_again = true;
  retried.reached = trace.reached;  // the poses of both searches
  if (pipeloc::work_candidate(again, surface, Deadline{f.deadline_hard, cancel_, interrupt}, &wk.retry_buf,
                              &retried, &slot_[std::size_t(c)])) {
    slot_filled_[std::size_t(c)] = 1;
    trace = retried;
    std::copy_n(wk.retry_ridge.begin(), retried.ridge_count, ridge);
  } else {
    trace.reached = retried.reached;
  }
  return retried.outcome != CandidateOutcome::budget;
}

}  // namespace pipeloc
