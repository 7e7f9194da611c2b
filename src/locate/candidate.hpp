// One candidate region through the paper's steps as named stages, each returning what it found:
// axis (III) -> observed ridge (IV-A) -> ridge fits (IV-B: slide the starts, probe, continue) ->
// hypotheses (beyond the paper: refine, verify, judge the twins) -> decide(). work_candidate()
// runs them and checks the deadline between them; decide() alone turns the evidence into the
// outcome.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <vector>

#include "core/camera.hpp"
#include "core/clock.hpp"
#include "locate/principal_axis.hpp"
#include "locate/regions.hpp"
#include "locate/ridge_icp.hpp"
#include "locate/starts.hpp"
#include "locate/surface_refine.hpp"
#include "locate/verify.hpp"

namespace pipeloc {

// Fewer observed ridge points than this give no fit worth the ICP (IV-A): a sliver of a region ...
constexpr int kMinRidgePoints = 10;
// ... or, for a short pipe, than cover this share of its length L (a 25 mm elbow's whole ridge is
// 12 cells of 2 mm), but never fewer than kLeastRidgePoints.
constexpr float kMinRidgeShareOfL = 0.4f;
constexpr int kLeastRidgePoints = 4;
inline int min_ridge_points(const LocateConfig& cfg, float extent_l_mm) {
  const int of_l = int(kMinRidgeShareOfL * extent_l_mm / float(cfg.ridge_cell_mm));
  return std::clamp(of_l, kLeastRidgePoints, kMinRidgePoints);
}
// Ranks verified hypotheses: a pixel the sensor saw through counts twice against the agreement,
// since a model lying over empty space is wrong however much else it covers.
constexpr float kFreeSpaceWeight = 2.0f;
// A hypothesis is a rival of the best (another reading of the same pipe) only where at least this
// share of its centreline lies within D/2 of the best's: readings of one pipe share 0.56-1.0 of it
// on the zoo, hypotheses on a neighbouring pipe none.
constexpr float kRivalMinSharedTube = 0.25f;
// Two poses within this * D of each other that share kRivalMinSharedTube of the tube are one
// pipe's (Locator::merge_estimate keeps one of them).
constexpr float kSamePipeOfD = 2.0f;
// Whether one of two poses puts at least kRivalMinSharedTube of its tube where the other has it.
inline bool share_the_tube(const LocatorModel& lm, const Pose& a, const Pose& b) {
  return shared_tube(lm, a, b) >= kRivalMinSharedTube || shared_tube(lm, b, a) >= kRivalMinSharedTube;
}
// An ambiguous estimate keeps half its score: it ranks below a sure one of about the same cover.
constexpr float kAmbiguousScoreFactor = 0.5f;
// A rival is told apart where at least kMinTellingPx pixels speak for the best and at most
// 1 / kTellingRatio of that for the rival (tell_apart). 10, not 20: a lone 12 mm S at 0.6-1 m
// shows 2-16 such pixels against its twin (docs/experiments.md).
constexpr int kMinTellingPx = 10;
constexpr int kTellingRatio = 4;
// The pixels telling two poses apart are read at this many sigmas of the frame's measured noise
// where that is finer than the verify tolerance (telling_tolerance_mm).
constexpr double kTellingToleranceOfSigma = 3.0;
// The depth difference that makes a pixel telling, and within which a reading speaks for a render.
float telling_tolerance_mm(const LocateConfig& cfg);

// judge_other_parts: at most this many other parts of the pipe a pose's part in view could be are
// judged ...
constexpr int kMostOtherParts = 2;
// ... where the part in view, moved onto it, lies within this * D of it (RMS): as a model's near
// twin lands within a quarter of D of itself (near_symmetry_tolerance_of_diameter).
constexpr float kOtherPartRmsOfD = 0.25f;

// Why an accepted pose is not handed out: one bit per check it fails (0 for a pickable pose). The
// overlay names the first bit set, in this order; `locate` and the timing log name them all.
enum Withheld : unsigned {
  kWithheldAmbiguous = 1u << 0,     // a rival the image judges about as well (a near twin, the pipe
                                    // slid along or turned about itself, one pipe read two ways)
  kWithheldCovered = 1u << 1,       // more than verify_max_occluded of it under something in front
  kWithheldPartSeen = 1u << 2,      // too much of it out of the view, or too little confirmed
  kWithheldGoesOn = 1u << 3,        // the tube goes on beyond both ends: the pipe lies elsewhere
  kWithheldNoEnd = 1u << 4,         // both ends in view, neither shown (pinned, the tube going
                                    // on beyond neither)
  kWithheldSecondSearch = 1u << 5,  // a second search's pose the image confirms too little
  kWithheldUnresolved = 1u << 6,    // the sensor does not resolve the tube (pick_min_relief_sigmas)
  kWithheldTookNothing = 1u << 7,   // handed out before, and its pick left the bin unchanged there
                                    // (the service's service.withhold_unchanged_picks)
};
constexpr int kWithheldKinds = 8;
// The place of the lowest of the first `kinds` bits set; `kinds` where none is.
constexpr int first_bit_index(unsigned bits, int kinds) {
  int k = 0;
  while (k < kinds && !(bits & (1u << k))) ++k;
  return k;
}
// The place of the first bit set, in Withheld's order: a bit's own place (the index of its count,
// CycleRecord::withheld, and of its name), or the first check a pose fails (the overlay's label);
// kWithheldKinds where none is set.
constexpr int withheld_index(unsigned bits) { return first_bit_index(bits, kWithheldKinds); }
// The bit's name (`ambiguous`, `covered`, `part_seen`, `goes_on`, `no_end`, `second_search`,
// `noisy`, `took_nothing`) and the overlay's label for it (AMBIGUOUS, COVERED, PART SEEN, GOES ON, NO END,
// UNSURE, NOISY, TOOK NOTHING); k-th bit for k in [0, kWithheldKinds).
const char* withheld_name(int k);
const char* withheld_label(int k);

// Why a pose is ambiguous: one bit per reason another pose fits about as well. `locate` names them
// all in `ambiguous_why`; the overlay adds the first to AMBIGUOUS.
enum Ambiguity : unsigned {
  kAmbiguousTwinUnresolved = 1u << 0,  // further than one pixel covers its near twin's spread
                                       // (twin_beyond_resolution_ambiguous): mount the camera nearer
  kAmbiguousRival = 1u << 1,           // a rival pose the image judges about as well and does not tell
                                       // apart (a near twin, the pipe slid or laid another way)
  kAmbiguousSlides = 1u << 2,          // the pipe, or its part in view, slides along itself and no
                                       // end seen ending places it
  kAmbiguousRoll = 1u << 3,            // a turn about its own length as good (judge_rolls)
  kAmbiguousOtherPart = 1u << 4,       // another part of the pipe could be its part in view
                                       // (judge_other_parts)
  kAmbiguousReadTwoWays = 1u << 5,     // one pipe read two ways by two regions (rivals_across_regions)
};
constexpr int kAmbiguityKinds = 6;
// The place of the first reason set (kAmbiguityKinds where none is); the bit's name
// (`twin_unresolved`, `rival`, `slides`, `roll`, `other_part`, `read_two_ways`) and the overlay's
// label for it (TWIN FAR, RIVAL, SLIDES, ROLL, OTHER PART, TWO WAYS); k-th bit.
constexpr int ambiguity_index(unsigned bits) { return first_bit_index(bits, kAmbiguityKinds); }
const char* ambiguity_name(int k);
const char* ambiguity_label(int k);

struct PipeEstimate {
  Pose model_to_bin = Pose::Identity();
  Pose model_to_cam = Pose::Identity();
  float score = 0;  // share of the model's silhouette the sensor confirms, lowered when occluded or ambiguous
  float ridge_cost_mm = 0;  // Algorithm 2 residual (mean truncated ridge distance)
  int ridge_points = 0;     // observed Z-ridge points of the region
  int refine_inliers = 0;
  int refine_points = 0;  // observed points the refinement used (the region's, or those the pose explains)
  float refine_rms_mm = 0;
  Verification check;
  unsigned ambiguous_why = 0;  // why another pose of the model fits about as well (Ambiguity bits)
  bool ambiguous() const { return ambiguous_why != 0; }
  bool pickable = false;   // accepted, not lying under another pipe, not ambiguous, its tube resolved
  int candidate = -1;      // index of its candidate region
  bool searched_again = false;  // found by its region's second search: picked only if no other is
  float relief_sigmas = 0;      // the tube's relief against the frame's noise (tube_relief_sigmas)
  bool unresolved = false;      // pickable but for that relief (pick_min_relief_sigmas)
  unsigned withheld = 0;        // why it is not pickable (Withheld bits; 0 where it is)
};

// How plainly the image shows a tube at a pose: the RMS by which a tube's top departs from the
// plane through it (0.223 R over its width, seen from above), summed in quadrature over the pixels
// confirming the pose, in sigmas of the frame's depth noise: sqrt(agree_px) 0.223 R / sigma.
float tube_relief_sigmas(const Verification& check, float tube_d_mm, float noise_mm);

// Why a candidate did not become an estimate.
enum class CandidateOutcome {
  accepted,
  few_ridge_points,
  residual_too_high,
  not_confirmed,
  duplicate,
  budget
};
const char* outcome_name(CandidateOutcome o);

// The poses a candidate reached on its way, for `locate --traces`: a missed pipe is traced to the
// stage that lost it (docs/experiments.md, "The held-out misses by stage"). Fixed capacity: the
// cycle fills them too, without allocating.
struct TracedPose {
  Pose model_to_bin = Pose::Identity();
  float value = 0;  // a ridge fit's residual (mm), a hypothesis' agreement
};
struct TracedPoses {
  static constexpr int kFits = 16, kHypotheses = 48;
  std::array<TracedPose, kFits> fits;              // the ridge fits continued, best ranked first
  std::array<TracedPose, kHypotheses> hypotheses;  // every refinement the image judged, in order
  int n_fits = 0, n_hypotheses = 0;
  int left_out = 0;  // beyond the capacity
  void add_fit(const Pose& p, float cost_mm) { add(&fits, &n_fits, p, cost_mm); }
  void add_hypothesis(const Pose& p, float agreement) { add(&hypotheses, &n_hypotheses, p, agreement); }

 private:
  template <std::size_t N>
  void add(std::array<TracedPose, N>* to, int* n, const Pose& p, float value) {
    if (*n < int(N))
      (*to)[std::size_t((*n)++)] = {p, value};
    else
      ++left_out;
  }
};

struct CandidateTrace {
  AxisEstimate axis;
  int ridge_begin = 0, ridge_count = 0;  // observed ridge points in Locator::ridge_points()
  Pose ridge_pose = Pose::Identity();    // after Algorithm 2, before refinement
  float ridge_cost_mm = 0;
  Pose refined_to_cam = Pose::Identity();  // the best refined fit, accepted or not
  Verification check;                      // of the best refined fit
  CandidateOutcome outcome = CandidateOutcome::budget;
  bool searched_again = false;  // the outcome is the second search's, on the whole top surface
  TracedPoses reached;          // of the first search and, where there was one, the second
};

// What decide() knows of a candidate: each stage adds its part.
enum class CandidateStage { axis, observed_ridge, ridge_fits, hypotheses };
struct Evidence {
  CandidateStage reached = CandidateStage::axis;  // the last stage done
  float tube_d_mm = 0;                            // D of the model
  float extent_l_mm = 0;                          // L of the model
  bool model_slides = false;                      // the model slides along itself (LocatorModel::slides)
  bool model_straight = false;                    // ... as a straight tube (LocatorModel::straight)
  bool ends_must_pin = false;                     // ... and its ends place it (pin_slides_by_ends)
  bool ends_judged = false;                       // the poses' ends were read (pin_slides_by_ends)
  bool has_ends = true;                           // ... the model has a centreline to read them by
  bool short_region = false;                      // the region was shorter than a * L
  bool searched_again = false;                    // the second search of the region (CandidateInput)
  int ridge_points = 0;                           // observed_ridge: observed Z-ridge points
  float least_ridge_cost_mm = 1e30f;              // ridge_fits: least residual of the states continued
  bool have_best = false, have_second = false;    // hypotheses: the best judged, and a rival
  Verification best, second;                      // ... more than ambiguity_pose_mm from it
  TellingPixels told;                             // ... the pixels where the image tells them apart
  bool roll_unsure = false;                       // ... the turn about its length not told (judge_rolls)
  bool rival_roll_unsure = false;                 // ... and so for the rival (judge_rolls)
  bool other_part_unsure = false;  // ... another part of the pipe in view as well (judge_other_parts)
  bool rival_other_part_unsure = false;  // ... and so for the rival (judge_other_parts)
  bool twin_unresolved = false;  // ... further from the camera than it resolves the near twin
  bool rival_ends_apart = true;  // ... their ends lie where judge_ends tells them (ends_tell_apart)
};

struct Decision {
  bool decided = false;  // false: the evidence so far passes every check it can answer
  CandidateOutcome outcome = CandidateOutcome::budget;
  unsigned ambiguous_why = 0;  // why it is ambiguous (Ambiguity bits; 0 where it is not)
  bool ambiguous() const { return ambiguous_why != 0; }
  bool pickable = false;
  float score = 0;
  bool rival_taken = false;  // the rival, not the best, is the pipe (its ends shown where they are)
  bool unresolved = false;   // pickable but for the tube's relief against the noise
  float relief_sigmas = 0;   // of the pose judged (tube_relief_sigmas)
  unsigned withheld = 0;     // why it is not pickable (Withheld bits)
};

// The outcome of a candidate from its evidence: the first check it fails (in the order of the
// stages), or accepted with ambiguity, pick and score once the hypotheses are judged (of the best,
// or of the rival where rival_taken). The checks are a table in candidate.cpp: a new verification
// check is one row there. ("duplicate" is the locator's, across candidates; "budget" is the
// outcome of a candidate never decided.)
Decision decide(const Evidence& evidence, const LocateConfig& cfg);

// Beyond the paper: a pose turned about the pipe's own length from the one found (judge_rolls)
// takes its place, where the image judges it better, only if the image shows its ends no worse
// (ends pinned, less twice those the tube goes on beyond). Where it does not, it still makes the
// turn unsure when about as good. A turn laid over a pipe running out of the view fits what is
// seen better than the pose it came from, whose end the image shows (23-planar of the zoo: a pick
// 330 mm off while clearing).
bool turn_may_replace(const Verification& turned, const Verification& found);
// judge_other_parts: whether another part of the pipe (`other`) shows its ends no worse than the
// pose (`found`), `shared` of the pose's ends lying where the other's do (ends_shared): an end both
// share pins neither more than the other. A pinned pose whose other part lies at both its ends is
// that pose moved less than the probes' reach, not another placement: false.
bool other_part_ends_no_worse(const Verification& other, const Verification& found, int shared);

// R_th of Algorithm 2: ridge fits with a larger residual are not pursued.
inline float residual_max_mm(const LocateConfig& cfg, float tube_d_mm) {
  return std::max(float(cfg.residual_max_of_d) * tube_d_mm, float(cfg.residual_noise_floor_mm));
}
// The residual up to which a region's ridge fits are pursued: R_th, or beyond the paper, where no
// fit of the region is under R_th, residual_rescue_of_rth x R_th (right fits of short or thin
// pipes lie just above R_th; the image judges them instead).
inline float pursued_residual_mm(const LocateConfig& cfg, float tube_d_mm, float least_cost_mm) {
  const float r_th = residual_max_mm(cfg, tube_d_mm);
  return least_cost_mm <= r_th ? r_th : float(std::max(1.0, cfg.residual_rescue_of_rth)) * r_th;
}
// The tube's width in pixels at the distance of the model's centroid (0 behind the camera).
inline double tube_px(const LocatorModel& lm, const Intrinsics& k, const Pose& model_to_cam) {
  const double z = (model_to_cam * lm.centroid.cast<double>()).z();
  return z > 0 ? lm.tube_d_mm * k.fx / z : 0;
}
// The free-space band of verify_pose() in pixels.
inline int free_space_band_px(const LocateConfig& cfg, const LocatorModel& lm, const Intrinsics& k,
                              const Pose& model_to_cam) {
  return int(cfg.free_space_band_of_d * tube_px(lm, k, model_to_cam) + 0.5);
}
// The side of a square of the silhouette seen through that rules a pose out: a quarter of the
// tube's width, at least 3 px (single pixels and pairs see through at edges and in noise).
inline int hole_side_px(const LocatorModel& lm, const Intrinsics& k, const Pose& model_to_cam) {
  return std::max(3, int(0.25 * tube_px(lm, k, model_to_cam) + 0.5));
}
// How well the image confirms a hypothesis: what ranks hypotheses and finds ambiguities. Two
// hypotheses of one region are compared on every pixel, the rim band included: where a
// near-symmetric pipe and its twin differ by a few millimetres, the band is what tells them apart.
inline float hypothesis_quality(const Verification& v) {
  return v.agreement() - kFreeSpaceWeight * v.free_space();
}
// Whether hypothesis `a` reads the image better than `b` (both of one region): the higher
// hypothesis_quality, but for a pipe its ends place (`ends_place`: it slides along itself, its
// slides are judged and slides_placed_first is on), of two the image confirms about as well, one an
// end pins with none going on beyond goes before one no end pins with the tube going on beyond an end.
bool better_reading(const Verification& a, const Verification& b, bool ends_place, const LocateConfig& cfg);
// Beyond the paper: two estimates of different regions that put the tube in one place over at
// least kRivalMinSharedTube of it, further apart than one pipe's duplicates, the image confirming
// them about as well, one of them reaching out of the view: one pipe read two ways
// (rivals_across_regions). Wholly in the view, each was checked on all of the pipe and judged
// against its own rivals.
bool read_two_ways(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                   const LocateConfig& cfg);
// Beyond the paper: of two such readings wholly in the view, each putting half of the tube where
// the other has it, the one whose ends the image shows better (ends pinned, less twice those the
// tube goes on beyond; for a pipe that slides along itself, ends seen ending outright) is the pipe,
// and the other no estimate of it: a 9 mm J bend's reading slid round its bend, one end shown,
// agreeing 0.98, was handed out 92 mm off before the right reading, both ends shown, agreeing 0.975
// (23-planar of the zoo). Returns the index (0: a, 1: b) of the reading the ends show worse, or -1
// where they do not tell.
int reading_its_ends_refute(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                            const LocateConfig& cfg);
// Beyond the paper: of two readings of one pipe by two regions, each putting half of the tube
// where the other has it, the one the image confirms clearly worse (not as_good) is no pick: the
// pipe lies where the better reading has it, whether or not that one is pickable (an arc's reading
// slid 31 mm round itself, one end seen ending, agreeing 0.87, was handed out while the right
// reading, agreeing 0.91, was withheld as sliding: 14-arc of the zoo). Returns the index (0: a,
// 1: b) of the reading confirmed worse, or -1.
int reading_read_worse(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                       const LocateConfig& cfg);

// The deadline a candidate's work stops at (a cancel flag, when set, ends it as well).
struct Deadline {
  Clock::time_point at = Clock::time_point::max();
  const std::atomic<bool>* cancel = nullptr;
  const std::atomic<bool>* interrupt = nullptr;  // a second flag (the second searches: a command waits)
  bool passed() const {
    return (cancel && cancel->load(std::memory_order_relaxed)) ||
           (interrupt && interrupt->load(std::memory_order_relaxed)) || Clock::now() >= at;
  }
};

// What the stages share from the model and the frame; read only.
struct CandidateContext {
  const PipeModel& model;
  const LocatorModel& lm;
  const StartSet& starts;
  const LocateConfig& cfg;
  const ZBuffer& zb;
  const Image<float>& depth;
  const Intrinsics& camera;
  Pose bin_to_cam;
  float lowest_surface_z_mm = NAN;  // bin frame: the floor where it is seen (LocateOutput)
  PixelBox view;                    // the pixels the sensor reads (read_view; LocateOutput)
};

struct CandidateTimes {
  double axis_ms = 0, ridge_icp_ms = 0, refine_ms = 0, verify_ms = 0;
};

// Per-thread working memory of the stages, sized once.
struct CandidateBuffers {
  AxisBuffers ab;
  RidgeBuffers ridge;  // for the observed ridges
  RidgeIcp icp;
  SlideBuffers slide;
  std::vector<Eigen::Vector3f> region_pts;
  std::vector<Eigen::Vector3f> explained_pts;   // capacity refine_max_points
  std::vector<Eigen::Vector3f> found_pts;       // ... those the best explains (its twins start on them)
  std::vector<Eigen::Vector3f> coarse_ridge;    // the region's Z-ridge on the probes' cells
  std::vector<Eigen::Vector3f> coarse_in_axis;  // the same in the frame of the observed axis
  std::vector<RidgeFit> fits;
  std::vector<SlidStart> starts;
  Image<float> scratch_depth;
  Image<float> rival_depth;  // the rival's render, beside the best's, to tell them apart
  ProjectedMesh scratch_mesh;
  CandidateTimes times;
};
// ridge_capacity: the most observed ridge points of a region; z_width, z_height: the Z-buffer's.
void reserve_candidate(CandidateBuffers* buf, const LocatorModel& lm, const StartSet& starts,
                       const LocateConfig& cfg, int max_region_cells, int ridge_capacity, int z_width,
                       int z_height, const Intrinsics& camera);

// The region a candidate works, and where its observed ridge goes.
struct CandidateInput {
  int index = -1;  // of the candidate region
  const CandidateRegion* region = nullptr;
  const int* cells = nullptr;  // its cells' indices in the Z-buffer
  Eigen::Vector3f* ridge = nullptr;
  int ridge_capacity = 0;
  bool searched_again = false;  // the second search of the region, on its whole top surface
};

// III: principal direction and initial position.
AxisEstimate find_axis(const CandidateContext& ctx, const CandidateInput& in, CandidateBuffers* buf);

// IV-A: the observed Z-ridge of the region, in in.ridge; the region's points stay in buf->region_pts.
struct ObservedRidge {
  int count = 0;          // ridge points
  int region_points = 0;  // in buf->region_pts
};
ObservedRidge observe_ridge(const CandidateContext& ctx, const CandidateInput& in, const AxisEstimate& axis,
                            CandidateBuffers* buf);

// IV-B, Algorithm 2: ridge ICP from the slid, probed and continued starts, in buf->fits ranked best
// first.
struct RidgeFits {
  bool complete = false;  // false: the deadline passed first
  Pose best_pose = Pose::Identity();
  float best_cost_mm = 1e30f;   // of the best ranked
  float least_cost_mm = 1e30f;  // least of all
};
RidgeFits fit_ridges(const CandidateContext& ctx, const CandidateInput& in, const AxisEstimate& axis,
                     const ObservedRidge& observed, const Deadline& deadline, CandidateBuffers* buf);

// Beyond the paper: the best few distinct fits under R_th and the twins of the best are refined
// on the region and judged by the depth image; the best two more than ambiguity_pose_mm apart.
struct Hypotheses {
  bool complete = false;  // false: the deadline passed first
  PipeEstimate best, second;
  bool have_best = false, have_second = false;
  TellingPixels told;  // for_a: pixels for the best, for_b: for the second
  // A hypothesis turned from another about the pipe's length (judge_rolls) is confirmed about as
  // well as the best and lies more than roll_ambiguity_mm from it.
  bool roll_unsure = false;
  // ... and so for a rival confirmed about as well, which decide() may take in the best's place.
  bool rival_roll_unsure = false;
  // The best reaches out of the view, and a pose putting another part of the pipe where its part
  // in view is seen is confirmed about as well on the pixels read (judge_other_parts).
  bool other_part_unsure = false;
  // ... and so for a rival confirmed about as well, which decide() may take in the best's place.
  bool rival_other_part_unsure = false;
};
Hypotheses judge_hypotheses(const CandidateContext& ctx, const CandidateInput& in,
                            const ObservedRidge& observed, const RidgeFits& fitted, const Deadline& deadline,
                            CandidateBuffers* buf, TracedPoses* reached);

// The stages in order, the deadline checked between them, decide() after each. Fills the trace;
// returns true with the estimate when the candidate is accepted.
bool work_candidate(const CandidateContext& ctx, const CandidateInput& in, const Deadline& deadline,
                    CandidateBuffers* buf, CandidateTrace* trace, PipeEstimate* estimate);

}  // namespace pipeloc
