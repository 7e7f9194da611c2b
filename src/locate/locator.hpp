// The localizer: one depth frame in, ranked pipe poses out. Every buffer is sized in the
// constructor from the camera and the model; locate() itself does not allocate.
#pragma once

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "core/camera.hpp"
#include "core/clock.hpp"
#include "core/worker_pool.hpp"
#include "locate/candidate.hpp"
#include "locate/thresholds.hpp"

namespace pipeloc {

struct StageTimes {
  double zbuffer_ms = 0, normals_ms = 0, regions_ms = 0, axis_ms = 0, ridge_icp_ms = 0, refine_ms = 0,
         verify_ms = 0, total_ms = 0;
  double again_ms = 0;  // of total_ms, the second searches after the pick (search_again())
};

struct LocateOutput {
  std::vector<PipeEstimate> estimates;  // ranked, best first; capacity max_candidates
  std::vector<CandidateTrace> traces;   // one per candidate region
  RegionStats regions;
  StageTimes times;
  int valid_pixels = 0;
  int speckles = 0;  // readings left out as speckles (remove_speckles)
  DepthNoise noise;  // measured in the frame when a threshold derives from it (else samples = 0)
  float lowest_surface_z_mm = 0;  // bin frame: the floor where it is seen (no pose lies below it)
  PixelBox view;  // the pixels the sensor reads: the image less its edges' dead bands (read_view)
  bool budget_exhausted = false;
  // The order the pickable poses are handed out in, lower first (-1: not handed out): the first
  // searches' before the second searches' (second_search_may_pick: those only where the first have
  // none), and of each, a pose its ends place before one they do not, in rank order. A pose is
  // placed so by an end the image shows ending, outright or but for the sensor's shadow, or by both
  // ends pinned (more than placed_by_ends() of the candidates asks: one pinned, none going on). A
  // pose pinned only past a hidden tip may lie slid along its pipe: an arc wholly in view so handed
  // out 30-57 mm round itself before a right pose of another arc with an end seen ending ranked
  // second (4 wrong picks clearing 3 bins). Pinned at both ends, a pose is placed as well: a 758 mm
  // arc so pinned, agreeing 0.96, was passed over for one seen ending at its one end in view,
  // handed out off every pipe (seed 20's 14-arc of the zoo). So is one whose end in view ends
  // beside the shadow it casts (the first probe past the tip unread, the second lower): coils and
  // arcs so placed, on their pipes, were passed over for poses seen ending elsewhere
  // (docs/experiments.md).
  static constexpr int kHandOutOrders = 4;
  static bool shown_ending_or_pinned_at_both_ends(const PipeEstimate& e) {
    return e.check.ends_shown_ending() > 0 || e.check.ends_pinned >= 2;
  }
  static int hand_out_order(const PipeEstimate& e) {
    if (!e.pickable) return -1;
    return (e.searched_again ? 2 : 0) + (shown_ending_or_pinned_at_both_ends(e) ? 0 : 1);
  }
  // Calls f(i) for each estimate handed out, in that order, until f returns false.
  template <typename F>
  void for_each_handed_out(F f) const {
    for (int order = 0; order < kHandOutOrders; ++order)
      for (std::size_t i = 0; i < estimates.size(); ++i)
        if (hand_out_order(estimates[i]) == order && !f(int(i))) return;
  }
  // The pose handed to the PLC: the first in that order. -1: none.
  int pick() const {
    int first = -1;
    for_each_handed_out([&](int i) {
      first = i;
      return false;
    });
    return first;
  }
};

class Locator {
 public:
  Locator(const PipeModel& model, const LocateConfig& cfg, const Intrinsics& camera);

  // Localizes pipes in depth_mm (0 = no reading). Candidates are worked best first; when the
  // deadline passes, what has been found so far is returned with budget_exhausted set.
  // locate_to_pick() and then search_again().
  const LocateOutput& locate(const Image<float>& depth_mm, const CameraInfo& camera,
                             Clock::time_point deadline = Clock::time_point::max());
  // Every search whose poses may be handed out: the pick (output().pick()) is final when it
  // returns. Where the first searches hand out none, that includes the second searches
  // (second_search_may_pick). depth_mm and camera must live until search_again() has run.
  const LocateOutput& locate_to_pick(const Image<float>& depth_mm, const CameraInfo& camera,
                                     Clock::time_point deadline = Clock::time_point::max());
  // The second searches of that frame (retry_surface_cell_of_d) before its deadline or until
  // *interrupt is set (the service: the PLC's next command waits), their poses merged and ranked
  // with the others: reported, never handed out, so the pick does not move (where there was none,
  // locate_to_pick() has run them already).
  const LocateOutput& search_again(const std::atomic<bool>* interrupt = nullptr);

  // A flag that, once set, ends a cycle as if its deadline had passed (the service's shutdown).
  void set_cancel_flag(const std::atomic<bool>* cancel) { cancel_ = cancel; }
  // Poses (model -> camera) handed out before whose picks left the bin unchanged there (the
  // service's TriedPicks): from the next frame on, an estimate within kTriedSameOfD D of one of
  // them (every check point, the model's symmetries taken into account; a straight tube's
  // centreline, since turned about its own length it is the same pick) is not pickable
  // (kWithheldTookNothing), so that the next pose, or the second searches, come first. At most
  // kMaxTried; the first n are kept.
  static constexpr int kMaxTried = 8;
  static constexpr float kTriedSameOfD = 0.5f;
  void set_tried(const Pose* model_to_cam, int n);

  const LocateOutput& output() const { return out_; }
  const ZBuffer& zbuffer() const { return zb_; }
  const RegionBuffers& regions() const { return rb_; }
  const std::vector<Eigen::Vector3f>& ridge_points() const { return ridge_pts_; }
  const LocatorModel& locator_model() const { return lm_; }
  const StartSet& starts() const { return starts_; }
  const LocateConfig& config() const { return cfg_; }  // the thresholds in effect for the last frame

 private:
  // Per-thread working memory for candidates.
  struct Worker {
    CandidateBuffers buf;
    CandidateBuffers retry_buf;  // for the second search of a region (retry_surface_cell_of_d) ...
    std::vector<Eigen::Vector3f> retry_ridge;  // ... and its observed surface cells
    int candidates_done = 0;  // this cycle, for the running average of a candidate's time
    double candidate_ms_sum = 0;
  };
  struct Frame {  // what the candidate tasks of one locate() share
    const Image<float>* depth;
    const CameraInfo* camera;
    Pose bin_to_cam;
    Clock::time_point deadline;       // begin no candidate after this
    Clock::time_point deadline_hard;  // stop a candidate's work after this
  };
  // Hands candidate regions from the thread growing them to the threads working them.
  struct Handout {
    Frame* frame = nullptr;
    Clock::time_point t_start;
    std::mutex mutex;
    std::condition_variable more;
    int found = 0, next = 0;  // candidates found so far; the next one to take up
    bool regions_done = false;
    double serial_ms = 0;  // from the start of the cycle to the last region
  };
  void regions_and_candidates(Handout& h, int task, int worker);
  void candidate_task(const Frame& f, int c, int worker);
  // What a candidate's search reads of the frame, with its starts and config; its region.
  CandidateContext context(const StartSet& starts, const LocateConfig& cfg, const Frame& f) const;
  CandidateInput candidate_input(int c);
  // The first search of candidate c; a region whose poses the image did not confirm is listed
  // for search_again().
  void work_candidate(int c, Worker& wk, const Frame& f);
  // The second search of the first n regions listed, on their whole top surface, before the
  // deadline (retry_surface_cell_of_d); of one region.
  // Each returns whether the search ran to its end (the deadline or *interrupt did not end it).
  bool search_regions_again(const Frame& f, int n, const std::atomic<bool>* interrupt);
  bool search_region_again(int c, Worker& wk, const Frame& f, const std::atomic<bool>* interrupt);
  // search_again()'s work: the regions listed searched again, their poses merged and ranked;
  // whether every one ran to its end (true where none was listed).
  bool second_searches(const std::atomic<bool>* interrupt);
  void merge_estimate(int c);
  void mark_pipes_read_two_ways();
  void mark_tried();
  // Candidates of what the accepted poses of candidates [0, n) left of their regions, worked
  // before the deadline (leftover_regions).
  void leftover_candidates(const Frame& f, int n);
  // Row bands of the frame-wide stages: band b of n covers rows [band_begin(b), band_begin(b + 1)).
  static int band_begin(int band, int bands, int rows) { return rows * band / bands; }
  void build_zbuffer_banded(const Image<float>& depth, const CameraInfo& camera, const Pose& bin_to_cam);
  void rank();

  const PipeModel& model_;
  LocateConfig user_cfg_;  // as configured: keys at 0 are derived (thresholds.hpp)
  LocateConfig cfg_;       // in effect this frame
  NoiseHistograms noise_histograms_;
  Image<float> depth_kept_;            // the frame less its speckles (remove_speckles)
  std::vector<int> height_histogram_;  // 1 mm bins, for the lowest surface
  std::vector<int> col_reads_, row_reads_;  // readings per column and row, for the view
  LocatorModel lm_;
  StartSet starts_;
  // The second search of a region whose ridge fits the image did not confirm: its config as
  // configured and in effect this frame, and its starts (empty when retry_surface_cell_of_d is 0).
  LocateConfig retry_user_cfg_, retry_cfg_;
  StartSet retry_starts_;
  bool retry_on_surface_ = false;
  std::vector<int> to_search_again_;    // candidates whose first search was not confirmed ...
  std::atomic<int> searches_again_{0};  // ... this many this frame
  Frame frame_{};                       // the frame locate_to_pick() worked, for search_again()
  Clock::time_point frame_start_{};     // when its locate_to_pick() began
  ZBuffer zb_;
  ZBufferPoints zb_points_;
  int camera_width_ = 0, camera_height_ = 0;
  NormalMap nm_;
  HoleList holes_;
  std::vector<int> band_holes_;  // per row band: its holes still listed
  RegionBuffers rb_;
  std::vector<Worker> workers_;
  WorkerPool pool_;
  std::vector<Eigen::Vector3f> ridge_pts_;  // observed ridges of all candidates
  std::vector<PipeEstimate> slot_;          // per candidate: its estimate, if accepted
  std::vector<char> slot_filled_;
  int first_leftover_ = 0;               // this frame's first candidate of a leftover region
  std::vector<std::uint8_t> explained_;  // per cell of a region: its pose explains it (leftover_candidates)
  LocateOutput out_;
  int ridge_capacity_ = 0;
  const std::atomic<bool>* cancel_ = nullptr;
  Pose tried_[kMaxTried];
  int tried_count_ = 0;
  double serial_ms_avg_ = 0, candidate_ms_avg_ = 0;  // running averages, for the anytime decisions
};

}  // namespace pipeloc
