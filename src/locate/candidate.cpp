#include "locate/candidate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

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

// Fewer explained pixels than this say too little to refine on.
constexpr int kMinExplainedPoints = 50;
// A pose the image confirms on less than this share of verify_min_agreement lies on no pipe: not
// refined again (the same zoo figures as refining every pose, at two thirds of the cost).
constexpr float kExplainedMinAgreementShare = 0.8f;

// Beyond the paper: the observed points a verified pose explains (its rendered silhouette, depth
// within the tolerance), in the bin frame, evenly thinned to the buffer's capacity: the whole
// pipe the image shows, where the region held only its top strip. `rendered` holds the depths
// render_depth_in_box() drew in `box`, and `drawn` the columns that render kept. Returns how many.
int explained_points(const CandidateContext& ctx, const Image<float>& rendered, const ProjectedMesh& drawn,
                     const PixelBox& box, float tol, std::vector<Eigen::Vector3f>* out) {
  const auto explained = [&](int x, int y) {
    const float zm = rendered.at(x, y), zo = ctx.depth.at(x, y);
    return zm > 0 && zo > 0 && std::abs(zo - zm) <= tol;
  };
  int count = 0;
  for (int y = box.y0; y <= box.y1; ++y) {
    const auto [from, to] = drawn.drawn_columns(box, y, rendered.height);
    for (int x = from; x <= to; ++x) count += explained(x, y);
  }
  const int capacity = int(out->size());
  const int stride = count / std::max(1, capacity) + 1;
  const Pose cam_to_bin = ctx.bin_to_cam.inverse();
  int seen = 0, n = 0;
  for (int y = box.y0; y <= box.y1; ++y) {
    const auto [from, to] = drawn.drawn_columns(box, y, rendered.height);
    for (int x = from; x <= to; ++x) {
      if (!explained(x, y) || seen++ % stride != 0 || n >= capacity) continue;
      (*out)[std::size_t(n++)] = (cam_to_bin * ctx.camera.unproject(x, y, ctx.depth.at(x, y))).cast<float>();
    }
  }
  return n;
}

// Whether any of the points (bin frame) is seen within kEdgeMarginPx of the view's border (the
// image less the sensor's dead bands: read_view).
constexpr double kEdgeMarginPx = 3;
bool reaches_view_edge(const CandidateContext& ctx, const Eigen::Vector3f* pts, int n) {
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector2d uv = ctx.camera.project(ctx.bin_to_cam * pts[k].cast<double>());
    if (uv.x() < ctx.view.x0 + kEdgeMarginPx || uv.y() < ctx.view.y0 + kEdgeMarginPx ||
        uv.x() > ctx.view.x1 - kEdgeMarginPx || uv.y() > ctx.view.y1 - kEdgeMarginPx)
      return true;
  }
  return false;
}

// RidgeFit::seen_through of a fit RidgeIcp::fit has just returned (its model ridge is still there).
float seen_through(const CandidateContext& ctx, const RidgeFit& f, const CandidateBuffers& buf) {
  return seen_through_share(ctx.zb, buf.icp.model_ridge(), f.model_ridge_points,
                            float(ctx.cfg.verify_tolerance_mm));
}

// A rival the image confirms about as well as the best: within ambiguity_quality_margin of it, or
// where the best covers few pixels, within this many standard errors of its agreement share (two
// poses' shares, each binomial over the best's pixels), the larger. A near twin of a 12 mm S
// 1.1-1.2 m away, on 150 pixels, agreed 0.06 below the best by chance (docs/experiments.md, "A
// quality margin no narrower than the agreement's noise").
constexpr float kQualityMarginErrors = 2.0f;
float quality_margin(const Verification& best, const LocateConfig& cfg) {
  float margin = float(cfg.ambiguity_quality_margin);
  if (best.model_px > 0) {
    const float p = std::clamp(best.agreement(), 0.0f, 1.0f);
    margin = std::max(margin, kQualityMarginErrors * std::sqrt(2.0f * p * (1.0f - p) / float(best.model_px)));
  }
  return margin;
}
bool as_good(const Verification& rival, const Verification& best, const LocateConfig& cfg) {
  return hypothesis_quality(rival) >= hypothesis_quality(best) - quality_margin(best, cfg);
}
// ... and the same judged on the pixels the sensor read (at least verify_min_read_share of each
// pose's counted): what lies where nothing is read speaks for neither (judge_other_parts). With
// in_front_left_out, only those where nothing lies in front: a rival whose part lies under another
// pipe is confirmed there no less than one stopping where that pipe begins (rivals_judged_where_seen).
bool as_good_where_read(const Verification& rival, const Verification& best, const LocateConfig& cfg,
                        bool in_front_left_out = false) {
  const float min_read = float(cfg.verify_min_read_share);
  const auto quality = [&](const Verification& v) {
    return v.read_agreement(min_read, in_front_left_out) - kFreeSpaceWeight * v.free_space();
  };
  return quality(rival) >= quality(best) - quality_margin(best, cfg);
}

// How well the image shows a pose's ends where they are: an end pinned speaks for it, the tube
// going on beyond an end (the pipe lies elsewhere along it) twice as much against.
int ends_shown(const Verification& v) { return v.ends_pinned - 2 * v.ends_continued; }
// ... and, for a pipe that slides along itself, only those seen ending outright count (a pin read
// past a hidden tip or on one probe is where a slid coil's end meets a pipe in front).
int ends_shown_outright(const Verification& v) { return v.ends_seen_ending - 2 * v.ends_continued; }

// The agreement the checks for a confirmed pose judge. Beyond the paper: a pose the image places
// by both its ends, each seen ending outright (the tip shown, every probe beyond it read and
// lower), is judged on what the sensor read of it: the pixels it did not read (a shadow, a glint
// hole) are neither for nor against, down to verify_min_read_share of the pipe counted. One end
// pinned is not enough: a coil slid along its helix, both ends stopped short by the pile, hid
// where it disagrees in unread pixels (a wrong pick in 12 coil bins), and so did poses over
// clutter in real frames without pipes (7 more picks). Choosing between hypotheses and the score
// still count unread pixels as not confirmed: of two poses, the one the image reads more of goes
// first.
float confirmed_agreement(const Verification& v, const LocateConfig& cfg) {
  const bool placed = v.ends_seen_ending >= 2 && v.ends_continued == 0;
  return placed ? v.read_agreement(float(cfg.verify_min_read_share)) : v.agreement();
}

// The image confirms the pose: verify_min_agreement of it (as confirmed_agreement counts).
bool confirmed_pose(const Verification& v, const LocateConfig& cfg) {
  return !(confirmed_agreement(v, cfg) < float(cfg.verify_min_agreement));
}

// Where the best's and a rival's renders differ, the pixels show `a` and hardly `b`: at least
// kMinTellingPx for it and at most 1 / kTellingRatio of that for the other.
bool pixels_show(int for_a, int for_b) { return for_a >= kMinTellingPx && kTellingRatio * for_b <= for_a; }

// The same evidence with the best and its rival in each other's place.
Evidence rival_first(Evidence e) {
  std::swap(e.best, e.second);
  std::swap(e.told.for_a, e.told.for_b);
  std::swap(e.roll_unsure, e.rival_roll_unsure);
  std::swap(e.other_part_unsure, e.rival_other_part_unsure);
  return e;
}

// A check of decide(): the candidate fails as `outcome` unless `passes`, once the evidence has
// reached `after`.
struct Check {
  CandidateStage after;
  CandidateOutcome outcome;
  bool (*passes)(const Evidence& e, const LocateConfig& cfg);
};

// decide()'s checks, in the order of the stages. A new check is a row here (and, if it needs
// evidence no stage gives yet, a field of Evidence that the stage fills).
constexpr Check kChecks[] = {
    {CandidateStage::observed_ridge, CandidateOutcome::few_ridge_points,
     [](const Evidence& e, const LocateConfig& cfg) {
       return e.ridge_points >= min_ridge_points(cfg, e.extent_l_mm);
     }},
    {CandidateStage::ridge_fits, CandidateOutcome::residual_too_high,
     [](const Evidence& e, const LocateConfig& cfg) {
       return e.least_ridge_cost_mm <= pursued_residual_mm(cfg, e.tube_d_mm, e.least_ridge_cost_mm);
     }},
    {CandidateStage::hypotheses, CandidateOutcome::not_confirmed,
     [](const Evidence& e, const LocateConfig& cfg) { return confirmed_pose(e.best, cfg); }},
    {CandidateStage::hypotheses, CandidateOutcome::not_confirmed,
     [](const Evidence& e, const LocateConfig& cfg) {
       return !(e.best.inner_free_space() > float(cfg.verify_max_free_space));
     }},
    {CandidateStage::hypotheses, CandidateOutcome::not_confirmed,
     [](const Evidence& e, const LocateConfig&) { return !e.best.seen_through_patch; }},
    // Beyond the paper: a smooth blob fits a pipe's top as well as a pipe does, but a pipe's sides
    // drop away from it. The level side pixels are counted out of at least kMinSidePx: a few read
    // (a pipe among shadows) say little, but a few mostly level still say blob (13 of 14 on a
    // real SR300 frame without pipes, handed out before: docs/experiments.md).
    {CandidateStage::hypotheses, CandidateOutcome::not_confirmed,
     [](const Evidence& e, const LocateConfig& cfg) {
       return !(e.best.side_level(kMinSidePx) > float(cfg.verify_max_side_level));
     }},
    // ... and no pipe lies under the floor.
    {CandidateStage::hypotheses, CandidateOutcome::not_confirmed,
     [](const Evidence& e, const LocateConfig&) { return !(e.best.below_floor > kMaxShareBelowFloor); }},
};

// The image's checks of a pose (kChecks' rows of the hypotheses stage): it would not be rejected
// as not confirmed.
bool image_accepts(const Verification& v, const LocateConfig& cfg) {
  Evidence e;
  e.reached = CandidateStage::hypotheses;
  e.have_best = true;
  e.best = v;
  for (const Check& check : kChecks)
    if (check.after == CandidateStage::hypotheses && !check.passes(e, cfg)) return false;
  return true;
}

// Of a pipe that slides along itself, a pose an end pins where none goes on beyond, and one no
// end pins where the tube goes on beyond one: the image shows the second slid along the pipe.
bool placed_by_ends(const Verification& v) { return v.ends_pinned > 0 && v.ends_continued == 0; }
bool shown_slid(const Verification& v) { return v.ends_pinned == 0 && v.ends_continued > 0; }

}  // namespace

// Beyond the paper: where part of the right pose lies in pixels the sensor did not read, the
// agreement alone prefers a pose slid along the pipe over them (the zoo's 31 mm coil, stereo: its
// top coil found 211 mm round its helix, agreeing 0.94, its right pose 0.90). Its ends tell them
// apart: the tube goes on beyond the slid one's end. Only between poses the image confirms about
// as well: a neighbour touching a right pose's end also reads as the tube going on.
bool better_reading(const Verification& a, const Verification& b, bool ends_place, const LocateConfig& cfg) {
  if (ends_place && confirmed_pose(a, cfg) && confirmed_pose(b, cfg)) {
    if (placed_by_ends(a) && shown_slid(b) && as_good(a, b, cfg)) return true;
    if (placed_by_ends(b) && shown_slid(a) && as_good(b, a, cfg)) return false;
  }
  return hypothesis_quality(a) > hypothesis_quality(b);
}

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

const char* withheld_name(int k) {
  static const char* const names[kWithheldKinds] = {
      "ambiguous", "covered", "part_seen", "goes_on", "no_end", "second_search", "noisy", "took_nothing"};
  return k >= 0 && k < kWithheldKinds ? names[k] : "?";
}

const char* ambiguity_name(int k) {
  static const char* const names[kAmbiguityKinds] = {"twin_unresolved", "rival",        "slides", "roll",
                                                     "other_part",      "read_two_ways"};
  return k >= 0 && k < kAmbiguityKinds ? names[k] : "?";
}

const char* ambiguity_label(int k) {
  static const char* const labels[kAmbiguityKinds] = {"TWIN FAR", "RIVAL",      "SLIDES",
                                                      "ROLL",     "OTHER PART", "TWO WAYS"};
  return k >= 0 && k < kAmbiguityKinds ? labels[k] : "?";
}

const char* withheld_label(int k) {
  static const char* const labels[kWithheldKinds] = {"AMBIGUOUS", "COVERED", "PART SEEN", "GOES ON",
                                                     "NO END",    "UNSURE",  "NOISY",     "TOOK NOTHING"};
  return k >= 0 && k < kWithheldKinds ? labels[k] : "?";
}

namespace {
// Half of the tube where the other has it, each way: two straight tubes touching end to end,
// each pose slid a little towards the other, share a quarter of it.
constexpr float kOneReadingMinSharedTube = 0.5f;

// Whether a and b, further apart than one pipe's duplicates, put one pipe's tube in one place:
// kRivalMinSharedTube of it one way or the other, or, where each_way_share is given, at least
// that share of it each way.
bool one_pipe_two_places(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                         float each_way_share = 0) {
  const Eigen::Vector3d ca = a.model_to_bin * lm.centroid.cast<double>(),
                        cb = b.model_to_bin * lm.centroid.cast<double>();
  // Every point of a pipe lies within L (the longest distance between two) of its centroid: two
  // more than 2 L + D apart share none of the tube.
  if ((ca - cb).norm() > 2.0 * double(lm.extent_l_mm) + double(lm.tube_d_mm)) return false;
  const float same_pipe_mm = kSamePipeOfD * lm.tube_d_mm;
  if (pose_distance_mm(lm, a.model_to_bin, b.model_to_bin, same_pipe_mm) <= same_pipe_mm) return false;
  if (!(each_way_share > 0)) return share_the_tube(lm, a.model_to_bin, b.model_to_bin);
  return shared_tube(lm, a.model_to_bin, b.model_to_bin) >= each_way_share &&
         shared_tube(lm, b.model_to_bin, a.model_to_bin) >= each_way_share;
}
// ... and the image confirms them about as well: one pipe read two ways.
bool one_pipe_two_readings(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                           const LocateConfig& cfg, float each_way_share = 0) {
  return as_good(a.check, b.check, cfg) && as_good(b.check, a.check, cfg) &&
         one_pipe_two_places(lm, a, b, each_way_share);
}
}  // namespace

bool read_two_ways(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                   const LocateConfig& cfg) {
  if (!(a.check.outside_view > 0) && !(b.check.outside_view > 0)) return false;
  return one_pipe_two_readings(lm, a, b, cfg);
}

int reading_its_ends_refute(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                            const LocateConfig& cfg) {
  if (a.check.outside_view > 0 || b.check.outside_view > 0 || !cfg.pin_slides_by_ends) return -1;
  if (!one_pipe_two_readings(lm, a, b, cfg, kOneReadingMinSharedTube)) return -1;
  const auto shown = [&](const Verification& v) {
    return lm.slides.empty() ? ends_shown(v) : ends_shown_outright(v);
  };
  const int sa = shown(a.check), sb = shown(b.check);
  return sa == sb ? -1 : sa < sb ? 0 : 1;
}

int reading_read_worse(const LocatorModel& lm, const PipeEstimate& a, const PipeEstimate& b,
                       const LocateConfig& cfg) {
  const bool a_as_good = as_good(a.check, b.check, cfg), b_as_good = as_good(b.check, a.check, cfg);
  if (a_as_good == b_as_good) return -1;
  if (!one_pipe_two_places(lm, a, b, kOneReadingMinSharedTube)) return -1;
  return a_as_good ? 1 : 0;
}

bool turn_may_replace(const Verification& turned, const Verification& found) {
  return ends_shown(turned) >= ends_shown(found);
}

bool other_part_ends_no_worse(const Verification& other, const Verification& found, int shared) {
  if (found.ends_pinned > 0 && shared == 2) return false;
  return ends_shown(other) >= ends_shown(found) - std::min(shared, found.ends_pinned);
}

Decision decide(const Evidence& given, const LocateConfig& cfg) {
  Decision out;
  // Beyond the paper: of two poses the image confirms about as well (a near twin), the one whose
  // ends it shows where they are is the pipe: a best by a hair whose end is not seen, or beyond
  // which the tube goes on, gives way to a rival the image pins; the checks below judge the
  // rival. So does a best whose ends the image shows no better where, of the pixels telling the
  // two apart, it shows the rival and hardly the best (a Z's twin with its legs swapped, one end
  // out of the view: 12-Z). Not for a pipe that slides along itself: in a pile, a slid coil's end
  // that stops short of a pipe in front reads as pinned (17-coil: 10 wrong picks while clearing
  // 3 bins).
  // The ends are compared only where they can tell the two apart: where the rival's lie within
  // the probes' reach of the best's, both are read beyond the same ends of the pipe, and one
  // pixel's noise chose (10-S-asym and 13-Z at 1.1-1.2 m, a twin's ends a third to two thirds of D
  // from the pipe's: of the picks on 480 images, 7 wrong ones gone and 7 right ones;
  // docs/experiments.md). Not for a pipe that slides along itself: its ends count only where seen
  // ending outright (below), and there the rule cost the zoo's arcs and coils 4 pipes taken while
  // clearing 3 bins, of none wrong.
  const bool ends_tell = given.ends_judged && (given.rival_ends_apart || given.model_slides);
  const bool pixels_take_rival = cfg.tell_rivals_apart && pixels_show(given.told.for_b, given.told.for_a) &&
                                 (!ends_tell || ends_shown(given.second) >= ends_shown(given.best));
  out.rival_taken = given.reached == CandidateStage::hypotheses && given.ends_judged &&
                    !given.ends_must_pin && given.have_best && given.have_second &&
                    as_good(given.second, given.best, cfg) &&
                    ((ends_tell && ends_shown(given.second) > ends_shown(given.best)) || pixels_take_rival);
  const Evidence e = out.rival_taken ? rival_first(given) : given;
  for (const Check& check : kChecks) {
    if (int(check.after) > int(e.reached)) break;
    if (!check.passes(e, cfg)) {
      out.decided = true;
      out.outcome = check.outcome;
      return out;
    }
  }
  if (e.reached != CandidateStage::hypotheses) return out;
  // A rival the image judges about as well makes the pipe ambiguous, whether or not it passes the
  // thresholds itself: the best passing them by a hair and a rival failing them by one are the same.
  out.decided = true;
  out.outcome = CandidateOutcome::accepted;
  // ... unless the image shows the best's ends where they are and not the rival's (a near twin
  // whose telling end is in view: beyond one of its ends the tube goes on, or it is not pinned).
  // ... or where the two differ, the image speaks for the best and hardly for the rival (not for
  // a pipe that slides along itself: its ends place it, below; but a straight tube whose ends
  // place it no worse than its rival's place it, an end seen ending outright and none going on:
  // one running out of the view, slid 1 mm from its pipe, 301 pixels for it and none for a rival
  // slid along it whose end met another tube).
  const int best_outright = ends_shown_outright(e.best);
  const bool straight_placed_as_rival = e.model_straight && best_outright >= 1 &&
                                        e.best.ends_continued == 0 &&
                                        best_outright >= ends_shown_outright(e.second);
  const bool told_apart = cfg.tell_rivals_apart && pixels_show(e.told.for_a, e.told.for_b) &&
                          (!e.ends_must_pin || straight_placed_as_rival);
  // A rival's end that goes on counts against it only where the pixels telling the two apart do
  // not speak for it half as much as for the best: another pipe touching the right pose's end
  // reads as its tube going on.
  const bool pixels_for_rival =
      cfg.tell_rivals_apart && e.told.for_b >= kMinTellingPx && 2 * e.told.for_b > e.told.for_a;
  const int rival_ends_shown = pixels_for_rival ? e.second.ends_pinned : ends_shown(e.second);
  // A pipe that slides along itself is told from its slid rival only by an end seen ending
  // outright: a pin read past a hidden tip or on one probe is where a slid coil's end meets a
  // pipe in front or the image's edge (17-coil, 12 bins, room for 32 candidates: 11 wrong picks).
  const int best_ends_shown = e.ends_must_pin ? best_outright : ends_shown(e.best);
  // Where the image pins none of the best's ends, the rival's part under something in front speaks
  // for neither: a Z's twin, its legs swapped, judged 0.06 worse for its longer leg under a pipe
  // crossing it, where the best stops, its other end out of the view: the best was handed out
  // 110 mm off while clearing (rivals_judged_where_seen; for every best, six bins of seed 19 took 40
  // pipes of 1978 fewer, with a wrong pick more: docs/experiments.md).
  const bool rival_as_good = as_good(e.second, e.best, cfg) ||
                             (cfg.rivals_judged_where_seen && e.best.ends_pinned == 0 &&
                              as_good_where_read(e.second, e.best, cfg, /*in_front_left_out=*/true));
  // Each rule that makes the pose ambiguous names itself (Ambiguity's bits: `locate`, the overlay).
  const auto ambiguous_if = [&out](bool holds, unsigned why) { out.ambiguous_why |= holds ? why : 0u; };
  ambiguous_if(
      e.have_second && rival_as_good && !(ends_tell && best_ends_shown > rival_ends_shown) && !told_apart,
      kAmbiguousRival);
  // Beyond the paper: a pipe that slides along itself is placed along its length only by an end
  // the image shows; where none is seen, or the tube goes on beyond one, the pose may be slid.
  ambiguous_if(e.ends_must_pin && (e.best.ends_pinned == 0 || e.best.ends_continued > 0), kAmbiguousSlides);
  // ... and so a pose whose part in the view slides along the pipe, reaching out of the view
  // (pin_part_in_view_by_ends): six bins of every shape handed out an arc's loop laid along
  // another part of its arc, pinned where its pipe ran under another, 237 mm off (15-arc of seed
  // 21); a long arc pinned past a pipe across its end, 40 mm round it (14-arc of seed 20); a coil's
  // loop at the image's edge, both ends out of the view, 82 mm off (18-coil of seed 21).
  ambiguous_if(e.best.part_in_view_slides && (e.best.ends_seen_ending == 0 || e.best.ends_continued > 0),
               kAmbiguousSlides);
  // ... and one whose turn about its own length the image does not tell (judge_rolls).
  ambiguous_if(e.roll_unsure, kAmbiguousRoll);
  // ... and one whose part in view another part of the pipe could be (judge_other_parts).
  ambiguous_if(e.other_part_unsure, kAmbiguousOtherPart);
  // ... and one further from the camera than where one pixel covers its near twin's spread
  // everywhere: no pixel can tell the two apart (twin_beyond_resolution_ambiguous).
  ambiguous_if(e.twin_unresolved, kAmbiguousTwinUnresolved);
  // An ambiguous pose further out of the view than any pose may be picked is not placed by the
  // image: neither its part out of the view nor its rival's is checked. It is no estimate (the
  // zoo's 16-arc, its arcs reaching out of the view: 10 of its 13 false estimates).
  const double most_out_of_view =
      std::max(cfg.verify_max_outside_view, cfg.verify_max_outside_view_well_seen);
  if (out.ambiguous() && e.best.outside_view > float(most_out_of_view)) {
    out.outcome = CandidateOutcome::not_confirmed;
    return out;
  }
  // The score is the share of the whole pipe the image confirms: what lies under others or out of
  // the view is not confirmed. A pose checked on all of the pipe goes before one reaching out of
  // the view that agrees as well where it is seen (its part out of view may lie elsewhere).
  out.score = e.best.agreement() * (1.0f - e.best.occluded()) * (1.0f - e.best.outside_view) *
              (out.ambiguous() ? kAmbiguousScoreFactor : 1.0f);
  // A pose is handed out only where the image could check it: at most verify_max_occluded of it
  // under something in front, at most verify_max_outside_view of it out of the view, and what
  // the image confirms is still verify_min_agreement of the whole pipe, the part out of the view
  // counted as not confirmed (a pose hanging out of the view is checked on too little of it) ...
  const float confirmed = confirmed_agreement(e.best, cfg);
  const float confirmed_of_whole = confirmed * (1.0f - e.best.outside_view);
  // ... or, up to verify_max_outside_view_well_seen of it out of the view, the image confirms
  // verify_well_seen_agreement of what is in view, and, where the ends are read, shows one of
  // them (none where both lie out of the view: no image shows them, and the bends in view place a
  // pipe that does not slide along itself; 24-planar of seed 20, a bend running out of the view
  // at both ends, agreeing 0.96, was its bin's last pipe left). What lies under something in
  // front (at most verify_max_occluded) may be left out of that share: an arc 7 % under another,
  // 34-42 % out of the view, agreed 0.88, 0.95 of what the image could see (the zoo's 16-arc); a
  // pipe that slides along itself is then well seen only where it shows an end seen ending
  // outright (a 16-arc pose 358 mm round its arc, one end pinned past its hidden tip, was handed
  // out). From a short region only for a pipe that does not slide along itself, its ends read and
  // one shown: a pipe that does, its top seen over a short length, may lie anywhere along it out
  // of the view; one that does not is placed by the bends in view and the end shown (23-planar of
  // the zoo: 3 more pipes taken in 3 bins). A pipe that slides is placed so only by its ends in
  // view, at least one, each seen ending outright, none going on, the others out of the view: a
  // long arc whose middle runs out of the view, both ends seen (14-arc of seed 20: 4 more arcs
  // taken while clearing its bin); a straight tube running out of the view at its other end
  // (01-straight of seed 20, 900 mm tubes: 5 -> 23 taken while clearing 3 bins); a long arc the
  // same (14-arc of seed 20: 17 -> 36 taken in six bins, no wrong pick more; arcs were left out
  // while a tip out of the view was still read and a part in view that slides was not judged:
  // their bins reached arcs pinned 7-21 mm round themselves; docs/experiments.md).
  // A straight tube is pinned there only by the probes beside its tip: one read further along it
  // alone leaves the tube room to go on, unread, between them (a tube 43 mm thick, its end in view
  // in the sensor's shadow at a crossing, picked 70 mm short of it).
  const int pinned_beside_tip = e.best.ends_pinned - (e.model_straight ? e.best.ends_pinned_further : 0);
  const float well_seen_share = float(cfg.verify_well_seen_agreement);
  const float unhidden = 1.0f - e.best.occluded();
  const bool well_seen =
      confirmed >= well_seen_share || (unhidden > 0 && confirmed / unhidden >= well_seen_share &&
                                       !(e.ends_must_pin && e.best.ends_seen_ending == 0));
  const int ends_seen_or_out = e.best.ends_seen_ending + e.best.ends_out_of_view;
  const bool short_but_placed =
      e.ends_judged &&
      (e.model_slides ? e.best.ends_seen_ending >= 1 && ends_seen_or_out >= 2 && e.best.ends_continued == 0
                      : e.best.ends_pinned > 0);
  // Of a pipe that does not slide, an end in view the image neither pins nor shows going on (no
  // reading there, or something in front) tells no more than an end out of the view. With the
  // other end out of the view, the bends in view place it, as they do where both ends lie out of
  // it (end_unread_as_out_of_view; a 3-D bend 0.4 mm off, agreeing 0.94, 28 % out of the view,
  // was withheld on its bin's last frame; six bins of every shape: 10 more pipes taken, no wrong
  // pick more).
  const bool ends_unshown_or_out =
      e.best.ends_out_of_view >= 2 ||
      (cfg.end_unread_as_out_of_view && !e.model_slides && !e.best.part_in_view_slides &&
       e.best.ends_out_of_view >= 1 && e.best.ends_continued == 0);
  // ... and where a pipe that does not slide along itself shows both its ends in view seen ending
  // outright, the tube going on beyond neither, its ends and the bends between them place it,
  // whatever its part out of the view: so well seen, up to verify_max_outside_view_ends_seen of it
  // may lie out of the view (a U or a planar bend whose middle runs out of the view, both ends
  // seen: right poses withheld on 19 frames where bins of the zoo stopped; twelve bins of every
  // shape took 30 more pipes of 06-U, 07-U, 23-planar and 24-planar, no wrong pick more;
  // docs/experiments.md).
  const bool placed_by_both_ends = e.ends_judged && !e.model_slides && !e.best.part_in_view_slides &&
                                   e.best.ends_seen_ending >= 2 && e.best.ends_continued == 0;
  const double most_out_well_seen = placed_by_both_ends ? std::max(cfg.verify_max_outside_view_well_seen,
                                                                   cfg.verify_max_outside_view_ends_seen)
                                                        : cfg.verify_max_outside_view_well_seen;
  const bool checked_in_view =
      (e.best.outside_view <= float(cfg.verify_max_outside_view) &&
       confirmed_of_whole >= float(cfg.verify_min_agreement)) ||
      ((!e.short_region || short_but_placed) && e.best.outside_view <= float(most_out_well_seen) &&
       well_seen && (!e.ends_judged || pinned_beside_tip > 0 || ends_unshown_or_out));
  // Beyond the paper: where the image shows the tube going on beyond both ends of the pose, the
  // pipe there is longer than the pose: it lies elsewhere along it (slid round a bend, across
  // two pipes).
  const bool ends_go_on = e.ends_judged && e.best.ends_continued >= 2;
  // ... and a pipe that does not slide along itself, wholly in the view, is placed by the image
  // only where it shows one of its ends ending there: of the picks on real frames without pipes,
  // 14 of 30 showed neither end (a pipe model laid over a hose, a handle, a box's edge); on the
  // zoo no image loses its pick (docs/experiments.md). Not for a model without a centreline (a
  // hollow STL whose bore hides it): its ends are never read.
  // Whether the pipe is wholly in the view is read at its ends: where both lie in it (and the way
  // on just beyond each: judge_ends()), a part of its middle out of the view does not excuse them
  // (end_shown_where_both_in_view; a coil's twin, 1 % of it out of the view, no end pinned, the
  // tube going on beyond one, was handed out 47 mm off after a shake: six bins of every shape of
  // the four draws, docs/experiments.md).
  // Where the tube goes on beyond one end, the other end must be seen ending outright: a pin read
  // past a hidden tip or on one probe does not outweigh it. Such poses laid a thin U or Z across
  // two pipes at 1.1-1.2 m, agreeing 0.92-0.93: 3 wrong picks of 374, where a pose within 5 mm
  // is now picked (docs/experiments.md); the zoo's picks are unchanged.
  const bool end_outweighed = e.best.ends_continued > 0 && e.best.ends_seen_ending == 0;
  const bool unplaced_in_view =
      e.ends_judged && e.has_ends && !e.model_slides &&
      (cfg.end_shown_where_both_in_view ? e.best.ends_out_of_view == 0 : !(e.best.outside_view > 0)) &&
      (e.best.ends_pinned == 0 || end_outweighed);
  // ... and a pose the second search of a region found, after the ridge's fits were not confirmed,
  // is handed out only where the first searches hand out none (LocateOutput::pick()), and only
  // where the image confirms verify_well_seen_agreement of what is in view and shows its sides
  // dropping away on at least kMinSidePx pixels: matched by its shape, a thin short elbow flipped
  // end for end fits its region as well (a wrong pick agreeing 0.98 while clearing 3 bins of
  // 04-elbow, where it could take a first search's place), and on real frames without pipes such
  // poses fit clutter, agreeing 0.74-0.86, or 0.94 on a 64-pixel elbow with 17 side pixels. What
  // lies under something in front (at most verify_max_occluded) is left out of that share, as for
  // a pose well seen: a coil 10 % under another agreeing 0.83 over all of it, 0.92 over the rest,
  // 0.8 mm from its pipe, was the last pose of a stopped bin (18-coil of seed 21).
  const bool second_search_placed = cfg.second_search_may_pick && unhidden > 0 &&
                                    !(e.best.agreement() / unhidden < well_seen_share) &&
                                    e.best.side_px >= kMinSidePx;
  // ... and only where the sensor resolves the tube (pick_min_relief_sigmas): a thin short elbow a
  // metre under an active-stereo sensor, its tube 1.3 sigmas of the noise in radius, agrees 0.9 at
  // poses 5-27 mm off (13 picks, 1 right); a pipe that is not a straight tube needs more
  // (pick_min_relief_sigmas_bent): thin short bends at 3.3-3.7 sigmas were picked 10 mm and more
  // off while clearing, thin straight tubes right (docs/experiments.md).
  out.relief_sigmas = tube_relief_sigmas(e.best, e.tube_d_mm, float(cfg.frame_noise_mm));
  const bool resolved = out.relief_sigmas >= float(cfg.min_relief(e.model_straight).sigmas);
  // Each check that holds the pose back is a bit: pickable where none is set; unresolved where the
  // relief alone is.
  const bool covered = e.best.occluded() > float(cfg.verify_max_occluded);
  const bool second_unsure = e.searched_again && !second_search_placed;
  out.withheld = (out.ambiguous() ? kWithheldAmbiguous : 0u) | (covered ? kWithheldCovered : 0u) |
                 (checked_in_view ? 0u : kWithheldPartSeen) | (ends_go_on ? kWithheldGoesOn : 0u) |
                 (unplaced_in_view ? kWithheldNoEnd : 0u) | (second_unsure ? kWithheldSecondSearch : 0u) |
                 (resolved ? 0u : kWithheldUnresolved);
  out.pickable = out.withheld == 0;
  out.unresolved = out.withheld == kWithheldUnresolved;
  return out;
}

// Beyond the paper: where the sensor's noise is low (a near pipe, a quiet sensor), a twin a few
// millimetres off shows in more pixels than the verify tolerance (7 mm, raised to the noise)
// lets tell: a lone 12 mm S's twin differs by a third of D at its ends. With the telling pixels
// read at 3 sigmas and 10 of them enough, the lone pipes (480 images) get 9 more picks, none
// wrong, and the zoo's picks are unchanged (docs/experiments.md).
float telling_tolerance_mm(const LocateConfig& cfg) {
  const double tol = cfg.verify_tolerance_mm;
  return float(cfg.frame_noise_mm > 0 ? std::min(tol, kTellingToleranceOfSigma * cfg.frame_noise_mm) : tol);
}

float tube_relief_sigmas(const Verification& check, float tube_d_mm, float noise_mm) {
  constexpr float kTopReliefRmsOfRadius = 0.223f;  // sqrt(2/3 - (pi/4)^2): sqrt(R^2 - x^2) on [-R, R]
  if (!(noise_mm > 0)) return 1e30f;
  return std::sqrt(float(check.agree_px)) * kTopReliefRmsOfRadius * 0.5f * tube_d_mm / noise_mm;
}

void reserve_candidate(CandidateBuffers* buf, const LocatorModel& lm, const StartSet& starts,
                       const LocateConfig& cfg, int max_region_cells, int ridge_capacity, int z_width,
                       int z_height, const Intrinsics& camera) {
  reserve_axis(&buf->ab, max_region_cells, z_width, z_height);
  reserve_ridge(&buf->ridge, lm.extent_l_mm + 2 * lm.tube_d_mm, float(cfg.ridge_cell_mm),
                std::max(max_region_cells, int(lm.ridge_samples.size())));
  buf->icp.reserve(lm, cfg, ridge_capacity);
  reserve_slide(&buf->slide, lm, ridge_capacity, float(cfg.ridge_cell_mm));
  buf->region_pts.assign(std::size_t(max_region_cells), Eigen::Vector3f::Zero());
  buf->explained_pts.assign(std::size_t(std::max(1, cfg.refine_max_points)), Eigen::Vector3f::Zero());
  buf->found_pts.assign(buf->explained_pts.size(), Eigen::Vector3f::Zero());
  buf->coarse_ridge.assign(std::size_t(ridge_capacity), Eigen::Vector3f::Zero());
  buf->coarse_in_axis.assign(std::size_t(ridge_capacity), Eigen::Vector3f::Zero());
  buf->fits.reserve(std::size_t(starts.size()));
  buf->starts.reserve(buf->fits.capacity());
  buf->scratch_depth.resize(camera.width, camera.height, 0.0f);
  buf->rival_depth.resize(camera.width, camera.height, 0.0f);
  buf->scratch_mesh.reserve(lm.verify_mesh, camera.height);
}

AxisEstimate find_axis(const CandidateContext& ctx, const CandidateInput& in, CandidateBuffers* buf) {
  const auto t = Clock::now();
  const CandidateRegion& region = *in.region;
  const AxisEstimate axis = estimate_axis(ctx.zb, in.cells, region.cells_end - region.cells_begin,
                                          region.core_centroid, ctx.cfg, ctx.lm.tube_d_mm, &buf->ab);
  buf->times.axis_ms += ms_since(t);
  return axis;
}

ObservedRidge observe_ridge(const CandidateContext& ctx, const CandidateInput& in, const AxisEstimate& axis,
                            CandidateBuffers* buf) {
  const auto t = Clock::now();
  ObservedRidge out;
  out.region_points = in.region->cells_end - in.region->cells_begin;
  const int w = ctx.zb.z.width;
  for (int k = 0; k < out.region_points; ++k)
    buf->region_pts[std::size_t(k)] = ctx.zb.point(in.cells[k] % w, in.cells[k] / w);
  out.count = extract_zridge(buf->region_pts.data(), out.region_points, axis.axis,
                             float(ctx.cfg.ridge_cell_mm), kRidgeMinRunOfD * ctx.lm.tube_d_mm, &buf->ridge,
                             in.ridge, in.ridge_capacity, ctx.cfg.match_surface);
  buf->times.ridge_icp_ms += ms_since(t);
  return out;
}

RidgeFits fit_ridges(const CandidateContext& ctx, const CandidateInput& in, const AxisEstimate& axis,
                     const ObservedRidge& observed, const Deadline& deadline, CandidateBuffers* buf) {
  const auto t = Clock::now();
  const LocateConfig& cfg = ctx.cfg;
  const LocatorModel& lm = ctx.lm;
  const StartSet& starts = ctx.starts;
  const float d = lm.tube_d_mm;
  RidgeFits out;
  std::vector<RidgeFit>& fits = buf->fits;
  fits.clear();
  // The probes rank the starts on coarser ridges of the same region.
  const float probe_cell = starts.cell_mm;
  const int n_coarse = extract_zridge(buf->region_pts.data(), observed.region_points, axis.axis, probe_cell,
                                      kRidgeMinRunOfD * d, &buf->ridge, buf->coarse_ridge.data(),
                                      in.ridge_capacity, cfg.match_surface);
  // Every start is slid to where it best covers the observed ridge ...
  const Pose axis_to_bin = axis_frame(axis);
  const Pose bin_to_axis = axis_to_bin.inverse();
  for (int k = 0; k < n_coarse; ++k)
    buf->coarse_in_axis[std::size_t(k)] =
        (bin_to_axis * buf->coarse_ridge[std::size_t(k)].cast<double>()).cast<float>();
  const RidgeView coarse{buf->coarse_ridge.data(), n_coarse, axis.axis, probe_cell};
  const RidgeView fine_ridge{in.ridge, observed.count, axis.axis, float(cfg.ridge_cell_mm)};
  buf->slide.observed_top.build(buf->coarse_ridge.data(), n_coarse, probe_cell, d);
  buf->starts.clear();
  // Beyond the paper: where the observed ridge reaches the view's edge, the pipe may lie anywhere
  // along it beyond the edge: the starts slide along edge_slide_along_of_l * L instead.
  const float along_mm = cfg.slide_starts && cfg.edge_slide_along_of_l > 0 &&
                                 reaches_view_edge(ctx, buf->coarse_ridge.data(), n_coarse)
                             ? float(cfg.edge_slide_along_of_l) * lm.extent_l_mm
                             : lm.slide_along_mm;
  for (int s = 0; s < starts.size(); ++s)
    buf->starts.push_back(slide_start(lm, starts, s, axis_to_bin, buf->coarse_in_axis.data(), n_coarse, cfg,
                                      &buf->slide, along_mm));
  // ... and those whose ridge covers it best are probed; the most promising continue to convergence.
  std::sort(buf->starts.begin(), buf->starts.end(),
            [](const SlidStart& a, const SlidStart& b) { return a.cost_mm < b.cost_mm; });
  if (int(buf->starts.size()) > cfg.icp_probed_states) buf->starts.resize(std::size_t(cfg.icp_probed_states));
  for (const SlidStart& st : buf->starts) {
    // A slow configuration probes long: the deadline (or a shutdown) is checked per start.
    if (deadline.passed()) {
      buf->times.ridge_icp_ms += ms_since(t);
      return out;
    }
    IcpStart start;
    start.pose = st.pose;
    start.model_ridge = starts.ridge(st.start), start.model_ridge_count = starts.ridge_count(st.start);
    fits.push_back(buf->icp.fit(start, coarse, cfg.icp_probe_iterations));
    fits.back().seen_through = seen_through(ctx, fits.back(), *buf);
  }
  const auto by_rank = [d](const RidgeFit& x, const RidgeFit& y) { return x.rank_cost(d) < y.rank_cost(d); };
  std::sort(fits.begin(), fits.end(), by_rank);
  // Several starts fall into the same basin: the states continued are distinct ones (more than
  // a diameter apart), so that a runner-up basin, the right one as often as not, is not crowded out.
  int distinct = 0;
  for (std::size_t i = 0; i < fits.size(); ++i) {
    bool seen = false;
    for (int j = 0; j < distinct && !seen; ++j)
      seen = pose_distance_mm(lm, fits[i].pose, fits[std::size_t(j)].pose, d) < d;
    if (!seen)
      std::rotate(fits.begin() + distinct, fits.begin() + long(i), fits.begin() + long(i) + 1), ++distinct;
  }
  // A pipe that slides along itself continues fewer: its further states are the same pipe slid a
  // little, which the image does not tell apart (twice as many: 15-arc 47 -> 45 on 18 images).
  const int continued = lm.slides.empty() ? cfg.icp_continued_states : cfg.icp_continued_states_sliding;
  const int keep = std::min(int(fits.size()), continued);
  for (int i = 0; i < keep; ++i) {
    if (deadline.passed()) {
      buf->times.ridge_icp_ms += ms_since(t);
      return out;
    }
    RidgeFit& f = fits[std::size_t(i)];
    // Continued on the coarse ridges, then the last icp_fine_iterations on the fine ones.
    const int left = std::max(1, cfg.icp_max_iterations - f.iterations);
    const int fine = std::min(left, cfg.icp_fine_iterations);
    if (left > fine)  // (not evaluated: the fine iterations go on from its pose at once)
      f = buf->icp.steps(IcpStart{f.pose, f.gate_mm}, coarse, left - fine);
    f = buf->icp.fit(IcpStart{f.pose, f.gate_mm}, fine_ridge, fine);
    f.seen_through = seen_through(ctx, f, *buf);
  }
  fits.resize(std::size_t(keep));
  if (deadline.passed()) {
    buf->times.ridge_icp_ms += ms_since(t);
    return out;
  }
  std::sort(fits.begin(), fits.end(), by_rank);
  buf->times.ridge_icp_ms += ms_since(t);
  out.complete = true;
  if (!fits.empty()) out.best_pose = fits[0].pose, out.best_cost_mm = fits[0].cost_mm;
  for (const RidgeFit& f : fits) out.least_cost_mm = std::min(out.least_cost_mm, f.cost_mm);
  return out;
}

Hypotheses judge_hypotheses(const CandidateContext& ctx, const CandidateInput& in,
                            const ObservedRidge& observed, const RidgeFits& fitted, const Deadline& deadline,
                            CandidateBuffers* buf, TracedPoses* reached) {
  const LocateConfig& cfg = ctx.cfg;
  const LocatorModel& lm = ctx.lm;
  const std::vector<RidgeFit>& fits = buf->fits;
  Hypotheses out;
  // The refinement needs far fewer points than the region holds: keep an even subset.
  const int count = observed.region_points;
  const int stride = std::max(1, count / cfg.refine_max_points);
  int refine_count = 0;
  for (int k = 0; k < count; k += stride)
    buf->region_pts[std::size_t(refine_count++)] = buf->region_pts[std::size_t(k)];

  // Beyond the paper: the least ridge residual is not always the right state (ridges of curved
  // pipes fit in more than one way). The best few distinct states under R_th (where none is, under
  // residual_rescue_of_rth x R_th) are refined on the whole region, point to plane, and the depth
  // image judges them (no floating, no sinking, no upside-down pipe). A runner-up the image
  // confirms about as well makes the pipe ambiguous.
  const float r_th = pursued_residual_mm(cfg, lm.tube_d_mm, fitted.least_cost_mm);
  const float ambiguity_mm = float(cfg.ambiguity_pose_mm);
  PipeEstimate &best = out.best, &second = out.second;
  bool &have_best = out.have_best, &have_second = out.have_second;
  // The pose whose render the scratch buffers hold (verify_at's last): the points the best
  // explains are read from it where it is the best's, not drawn again (the same depths). Whatever
  // else draws into the scratch (telling_pixels) clears scratch_holds_pose.
  Pose scratch_pose = Pose::Identity();
  PixelBox scratch_box;  // ... and the box it was drawn in
  bool scratch_holds_pose = false;
  // The image's judgement of a pose (model to camera); renders into the scratch buffers.
  const auto verify_at = [&](const Pose& model_to_cam) {
    const Verification v =
        verify_pose(lm.verify_mesh, lm.verify_winding, model_to_cam, ctx.depth, ctx.camera,
                    float(cfg.verify_tolerance_mm), float(cfg.side_drop_of_d) * lm.tube_d_mm,
                    free_space_band_px(cfg, lm, ctx.camera, model_to_cam), &buf->scratch_depth,
                    &buf->scratch_mesh, hole_side_px(lm, ctx.camera, model_to_cam), &ctx.view);
    scratch_pose = model_to_cam, scratch_box = v.box, scratch_holds_pose = true;
    return v;
  };
  // Where the renders of two poses differ, the pixels that show each (tell_apart); renders into
  // the scratch and rival buffers.
  const auto telling_pixels = [&](const PipeEstimate& a, const PipeEstimate& b) {
    const auto t0 = Clock::now();
    scratch_holds_pose = false;
    const PixelBox box_a = render_depth_in_box(lm.verify_mesh, a.model_to_cam, ctx.camera,
                                               &buf->scratch_depth, &buf->scratch_mesh, lm.verify_winding);
    const PixelBox box_b = render_depth_in_box(lm.verify_mesh, b.model_to_cam, ctx.camera, &buf->rival_depth,
                                               &buf->scratch_mesh, lm.verify_winding);
    const TellingPixels told =
        tell_apart(buf->scratch_depth, box_a, buf->rival_depth, box_b, ctx.depth, telling_tolerance_mm(cfg));
    buf->times.verify_ms += ms_since(t0);
    return told;
  };
  // Two readings of one pipe: more than ambiguity_pose_mm apart, and sharing at least
  // kRivalMinSharedTube of the tube. A hypothesis that shares less lies on another pipe (a ridge
  // fit reaching a neighbour): the image confirming both says nothing against either.
  const auto rivals = [&](const PipeEstimate& a, const PipeEstimate& b) {
    return pick_distance_mm(lm, a.model_to_bin, b.model_to_bin, ambiguity_mm) > ambiguity_mm &&
           shared_tube(lm, a.model_to_bin, b.model_to_bin) >= kRivalMinSharedTube;
  };
  // Beyond the paper: the refinement reads points as the camera saw them (refine_facing_only,
  // refine_ray_pairs).
  const Eigen::Vector3f camera_bin = ctx.bin_to_cam.inverse().translation().cast<float>();
  // The image's reading of a pose's ends, and how much of it lies below the floor.
  EndReading end_reading;
  end_reading.tip_must_show = lm.slides.empty();
  end_reading.read_further = cfg.ends_read_further && !lm.slides.empty();
  end_reading.slanted = cfg.ends_read_slanted;
  // Not for a pipe that slides along itself: its ends alone place it, and a probe moved out pins a
  // tip less tightly (a tube ending anywhere short of it reads the same): six bins of every shape
  // took 5 more pipes with 6 more wrong picks on elbows, arcs and coils (docs/experiments.md).
  end_reading.past_itself = cfg.ends_probed_past_itself && lm.slides.empty();
  const auto read_ends_and_floor = [&](PipeEstimate* e) {
    if (cfg.pin_slides_by_ends)
      judge_ends(lm.centreline_points, lm.tube_d_mm, e->model_to_cam, ctx.depth, ctx.camera,
                 float(cfg.verify_tolerance_mm), &e->check, end_reading, &ctx.view);
    // Slid D along itself, or the ambiguity distance where D is less (nearer, the same pick).
    if (cfg.pin_part_in_view_by_ends && e->check.outside_view > 0)
      judge_part_in_view(lm.centreline_points, lm.centreline_step_mm, lm.tube_d_mm,
                         std::max(lm.tube_d_mm, float(cfg.ambiguity_pose_mm)), e->model_to_cam, ctx.camera,
                         &e->check, &ctx.view);
    if (!std::isnan(ctx.lowest_surface_z_mm))
      e->check.below_floor = share_below(lm.verify_mesh, e->model_to_bin,
                                         ctx.lowest_surface_z_mm - kBelowFloorOfD * lm.tube_d_mm);
  };
  // Refines a hypothesis on observed points (the region's; a twin's, those the best explains) and
  // has the image judge it. Where start_may_stay, the start itself is judged too and kept where the
  // image judges it better than its refinement.
  const auto refine_and_check = [&](const Pose& start, float ridge_cost_mm, const Eigen::Vector3f* points,
                                    int n_points, bool start_may_stay = false) {
    auto t0 = Clock::now();
    RefineResult refined = refine_on_surface(lm, start, points, n_points, cfg, camera_bin);
    int refined_on = n_points;
    buf->times.refine_ms += ms_since(t0);
    t0 = Clock::now();
    PipeEstimate e;
    e.model_to_bin = refined.pose;
    e.model_to_cam = ctx.bin_to_cam * refined.pose;
    e.check = verify_at(e.model_to_cam);
    reached->add_hypothesis(e.model_to_bin, e.check.agreement());
    // Another reading of the same hypothesis takes e's place where the image judges it better.
    const auto take_if_better = [&](const Pose& to_bin, const Pose& to_cam, const Verification& v) {
      if (hypothesis_quality(v) <= hypothesis_quality(e.check)) return false;
      e.model_to_bin = to_bin;
      e.model_to_cam = to_cam;
      e.check = v;
      return true;
    };
    // Beyond the paper: refined again on all the image shows of the pipe where this pose put it
    // (the region holds only its top strip, along which a leg can slide); kept if judged better.
    if (cfg.refine_on_explained &&
        e.check.agreement() >= kExplainedMinAgreementShare * float(cfg.verify_min_agreement)) {
      const int n = explained_points(ctx, buf->scratch_depth, buf->scratch_mesh, e.check.box,
                                     float(cfg.verify_tolerance_mm), &buf->explained_pts);
      if (n >= kMinExplainedPoints) {
        buf->times.verify_ms += ms_since(t0);
        t0 = Clock::now();
        const RefineResult again =
            refine_on_surface(lm, refined.pose, buf->explained_pts.data(), n, cfg, camera_bin);
        buf->times.refine_ms += ms_since(t0);
        t0 = Clock::now();
        const Pose again_to_cam = ctx.bin_to_cam * again.pose;
        const Verification v = verify_at(again_to_cam);
        reached->add_hypothesis(again.pose, v.agreement());
        if (take_if_better(again.pose, again_to_cam, v)) refined = again, refined_on = n;
      }
    }
    if (start_may_stay) {
      const Pose start_to_cam = ctx.bin_to_cam * start;
      take_if_better(start, start_to_cam, verify_at(start_to_cam));
    }
    // The poses' ends are read for every pipe: a pipe that slides along itself or has a near
    // twin is placed by its ends, and where the tube goes on beyond both ends of a pose the pipe
    // lies elsewhere. A pipe that does not slide is shown ending only where its tip is seen: a
    // near twin overshooting the pipe's end under a pipe lying across it was pinned by the floor
    // beyond and taken for the pipe (23-planar of the zoo, 12 bins: 3 wrong picks). Not for
    // sliding pipes, whose ends alone place them: there it costs 17-coil 12 of 51 pipes taken in
    // 3 bins, with no wrong pick fewer. Their ends are read further along the bend where nothing
    // is read just beyond them (ends_read_further).
    read_ends_and_floor(&e);
    buf->times.verify_ms += ms_since(t0);
    e.ridge_cost_mm = ridge_cost_mm;
    e.ridge_points = observed.count;
    e.refine_inliers = refined.inliers;
    e.refine_points = refined_on;
    e.refine_rms_mm = refined.rms_mm;
    e.candidate = in.index;
    return e;
  };
  // Without slid rivals a pose put first by an end pinned wrongly is checked by nothing: the zoo's
  // 31 mm coil, the paper's search, got a pick 197 mm round its helix.
  const bool ends_place =
      cfg.slides_placed_first && cfg.judge_slides && cfg.pin_slides_by_ends && !lm.slides.empty();
  // Keeps the best two hypotheses that are more than ambiguity_pose_mm apart. Returns the
  // hypothesis as judged. A turn of the found pose about its length replaces it only as
  // turn_may_replace() says; a twin that may stay is kept unrefined where the image judges its
  // start better (below).
  enum class Start { hypothesis, turn, twin_may_stay };
  const auto judge = [&](const Pose& start, float ridge_cost_mm, const Eigen::Vector3f* points, int n_points,
                         Start kind = Start::hypothesis) {
    const PipeEstimate e =
        refine_and_check(start, ridge_cost_mm, points, n_points, kind == Start::twin_may_stay);
    if (kind == Start::turn && have_best && !turn_may_replace(e.check, best.check)) return e;
    if (!have_best || better_reading(e.check, best.check, ends_place, cfg)) {
      if (have_best && rivals(best, e))
        second = best, have_second = true;
      else if (have_second && !rivals(second, e))
        have_second = false;  // a rival of a best on another pipe
      best = e, have_best = true;
    } else if ((!have_second || better_reading(e.check, second.check, ends_place, cfg)) && rivals(e, best)) {
      second = e, have_second = true;
    }
    return e;
  };
  int tried = 0;
  for (std::size_t i = 0; i < fits.size() && tried < cfg.verify_hypotheses; ++i) {
    if (fits[i].cost_mm > r_th) continue;
    bool seen = false;
    for (std::size_t j = 0; j < i && !seen; ++j)
      seen = fits[j].cost_mm <= r_th &&
             pick_distance_mm(lm, fits[i].pose, fits[j].pose, ambiguity_mm) < ambiguity_mm;
    if (seen) continue;
    if (deadline.passed()) return out;  // an unchecked runner-up could hide an ambiguity
    ++tried;
    judge(fits[i].pose, fits[i].cost_mm, buf->region_pts.data(), refine_count);
  }
  // The points the best explains, in buf->found_pts, if enough to refine on (else 0).
  // Only the best's render is read: drawn where the scratch holds another's, not judged again.
  const auto explained_by_best = [&] {
    const auto t0 = Clock::now();
    if (!scratch_holds_pose || !(scratch_pose.matrix() == best.model_to_cam.matrix())) {
      scratch_box = render_depth_in_box(lm.verify_mesh, best.model_to_cam, ctx.camera, &buf->scratch_depth,
                                        &buf->scratch_mesh, lm.verify_winding);
      scratch_pose = best.model_to_cam, scratch_holds_pose = true;
    }
    const int n = explained_points(ctx, buf->scratch_depth, buf->scratch_mesh, scratch_box,
                                   float(cfg.verify_tolerance_mm), &buf->found_pts);
    buf->times.verify_ms += ms_since(t0);
    return n < kMinExplainedPoints ? 0 : n;
  };
  // Beyond the paper: a near-symmetric part (a half-turn maps most of it onto itself) seen only
  // where the two poses agree fits both equally; the ridge ICP need not have reached the other.
  // The twin of the best hypothesis is judged too, so that the ambiguity is found, or the twin
  // taken when the image prefers it. A twin is refined on all the image shows of the pipe the
  // best lies on, where the region's top strip may hold too little of it: a twin a leg's
  // difference away slides off a strip, not off the whole pipe. A twin that wins has its own twin
  // judged in turn (the first best may itself have been a twin badly placed), at most
  // kTwinRounds times. A twin of a pipe that slides along itself stays where the half-turn puts it
  // where the image judges that better than its refinement: refined on the points the best
  // explains, a 10.2 mm elbow's twin agreeing 0.89 was moved off its pipe to 0.52 (the zoo's
  // 04-elbow; docs/experiments.md). Not for other pipes: a near twin kept unrefined is handed out
  // in its pipe's place (23-planar of seed 21: 2 wrong picks). A twin of a pipe that does not
  // slide is refined on the region as well (twins_refined_on_region), each refinement judged as a
  // hypothesis: what the best explains is where the best put the pipe, and a twin refined only
  // there can stay short of its own place. A 57 mm S of 9.4 mm tube, 61 mm off, was the pick: its
  // twin refined on what it explained agreed 0.93 and saw through 0.07, on the region 0.96 and
  // 0.04, as well as the pose, which is now ambiguous (11-S-asym of seed 21; twelve bins of every
  // shape: docs/experiments.md).
  constexpr int kTwinRounds = 4;
  const Start twin_start = lm.slides.empty() ? Start::hypothesis : Start::twin_may_stay;
  for (int round = 0; have_best && round < kTwinRounds && !ctx.model.near_symmetries.empty(); ++round) {
    const Pose found = best.model_to_bin;  // judging a twin may replace the best: twins of this one
    const float found_cost_mm = best.ridge_cost_mm;
    const int found_count = cfg.refine_on_explained ? explained_by_best() : 0;
    for (const Pose& half_turn : ctx.model.near_symmetries) {
      const Pose twin = found * half_turn;
      // A runner-up the region refined stands for the twin only if the twin is refined there too.
      if (found_count == 0 && have_second &&
          pick_distance_mm(lm, twin, second.model_to_bin, ambiguity_mm) <= ambiguity_mm)
        continue;
      if (deadline.passed()) return out;
      judge(twin, found_cost_mm, found_count > 0 ? buf->found_pts.data() : buf->region_pts.data(),
            found_count > 0 ? found_count : refine_count, twin_start);
      if (cfg.twins_refined_on_region && found_count > 0 && lm.slides.empty()) {
        if (deadline.passed()) return out;
        judge(twin, found_cost_mm, buf->region_pts.data(), refine_count, twin_start);
      }
    }
    if (pick_distance_mm(lm, found, best.model_to_bin, ambiguity_mm) <= ambiguity_mm) break;  // it held
  }
  // Beyond the paper: the best turned about the pipe's own length by quarter turns (eighths where a
  // quarter turn lands the pipe mostly on itself; LocatorModel::rolls), each refined:
  // where the image confirms another turn about as well and it moves the pick beyond
  // roll_ambiguity_mm, the pipe's turn is not known to the pick's tolerance; unless, where the two
  // differ, the pixels show the best and hardly the turn, as they tell a rival (tell_rolls_apart).
  // A coil of 1.25 turns turned half about its length lies nearly where it was: seed 21's 18-coil
  // of the zoo (8.3 mm, 0.48 m under the stereo sensor) had its right poses ambiguous so, its bin
  // stopped with 14 coils free (docs/experiments.md). A rival as good is judged so too, below.
  const float roll_mm = float(cfg.roll_ambiguity_mm);
  // Whether `turn` leaves the turn of `found` not known: confirmed about as well, the pick moved
  // beyond roll_mm, and not told apart by the pixels.
  const auto turn_as_good = [&](const PipeEstimate& found, const PipeEstimate& turn) {
    if (!as_good(turn.check, found.check, cfg) ||
        !(pick_distance_mm(lm, found.model_to_bin, turn.model_to_bin, roll_mm) > roll_mm))
      return false;
    if (cfg.tell_rolls_apart) {
      const TellingPixels told = telling_pixels(found, turn);
      if (pixels_show(told.for_a, told.for_b)) return false;  // the image shows the pose, not the turn
    }
    return true;
  };
  if (cfg.judge_rolls && have_best && !lm.rolls.empty()) {
    constexpr std::size_t kTurns = 1 + LocatorModel::kMostRolls;  // the best and its turns
    PipeEstimate turned[kTurns];
    std::size_t n_turned = 0;
    turned[n_turned++] = best;
    const Pose found = best.model_to_bin;
    const float found_cost_mm = best.ridge_cost_mm;
    for (std::size_t k = 0; k < lm.rolls.size() && n_turned < kTurns; ++k) {
      if (deadline.passed()) return out;
      turned[n_turned++] =
          judge(found * lm.rolls[k], found_cost_mm, buf->region_pts.data(), refine_count, Start::turn);
    }
    for (std::size_t k = 0; k < n_turned && !out.roll_unsure; ++k)
      out.roll_unsure = turn_as_good(best, turned[k]);
  }
  if (have_best) {
    const Pose found = best.model_to_bin;  // the best after its twins: slid poses of this one
    const float found_cost_mm = best.ridge_cost_mm;
    // Beyond the paper: a pipe slid along itself (an arc about its centre, a coil along its helix)
    // shows the same surface wherever its ends are not seen: the slid poses are rivals too.
    // Far slides only for a pose the image confirms: they look for its twin along the pipe, not
    // for the pipe (the same zoo figures, 5-9 % less time on arcs and coils).
    const bool confirmed = confirmed_pose(best.check, cfg);
    for (std::size_t k = 0; cfg.judge_slides && k < lm.slides.size(); ++k) {
      if (k >= lm.short_slides && !confirmed) break;
      const Pose slid = found * lm.slides[k];
      if (have_second && pick_distance_mm(lm, slid, second.model_to_bin, ambiguity_mm) <= ambiguity_mm)
        continue;
      if (deadline.passed()) return out;
      judge(slid, found_cost_mm, buf->region_pts.data(), refine_count);
    }
  }
  // A pose moved along its pipe is judged by the pixels the image confirms less those it sees
  // through (follow_slides_to_ends, place_slides_finely) ...
  const auto confirmed_less_seen_through = [](const Verification& v) { return v.agree_px - v.free_space_px; };
  // ... judged where it lies, not refined again (refined, it would slide back) ...
  const auto slid_best = [&](const Pose& found, const Pose& slide, const Verification& check) {
    PipeEstimate slid = best;
    slid.model_to_bin = found * slide;
    slid.model_to_cam = ctx.bin_to_cam * slid.model_to_bin;
    slid.check = check;
    return slid;
  };
  // ... and, where it replaces the best, a second it now lies within the ambiguity distance of
  // is the same reading, no rival.
  const auto moved_best_to = [&](const PipeEstimate& moved) {
    best = moved;
    if (have_second && !rivals(best, second)) have_second = false;
  };
  // Beyond the paper: a pose of a pipe that slides along itself, beyond one of whose ends the
  // tube goes on and neither of which the image pins, lies slid along its pipe; the slides
  // judged above reach at most 5 steps, and refined, a slid pose slides back along the strip. It
  // is moved along itself by D, 2 D, ... both ways as far as the far slides (follow_slides) and,
  // where the image accepts the moved pose and shows one of its ends ending outright, none going
  // on, put where the image confirms the most of it and sees through the least of it. A pose
  // pinned only past a hidden tip is not taken: a 758 mm arc so followed was handed out 13 mm
  // along its arc while clearing (tools/zoo --seed 20, 14-arc). On the held-out zoos (1 bin each)
  // 6 more pipes taken while clearing bins of arcs and straight tubes, and a wrong pick of 14-arc
  // gone (docs/experiments.md).
  if (cfg.follow_slides_to_ends && have_best && !lm.follow_slides.empty() && shown_slid(best.check) &&
      !deadline.passed()) {
    const Pose found = best.model_to_bin;
    const auto t0 = Clock::now();
    PipeEstimate followed;
    bool have_followed = false;
    for (const Pose& s : lm.follow_slides) {
      const Verification v = verify_at(ctx.bin_to_cam * (found * s));
      if (!image_accepts(v, cfg)) continue;
      PipeEstimate slid = slid_best(found, s, v);
      read_ends_and_floor(&slid);
      if (!placed_by_ends(slid.check) || slid.check.ends_seen_ending == 0) continue;
      if (!have_followed ||
          confirmed_less_seen_through(slid.check) > confirmed_less_seen_through(followed.check))
        followed = slid, have_followed = true;
    }
    if (have_followed) moved_best_to(followed);
    buf->times.verify_ms += ms_since(t0);
  }
  // Beyond the paper: a pipe that slides along itself is placed along its length by its ends, and
  // the slides judged above are max(10 mm, D/2) apart: a pose its ends pin is moved along itself
  // in steps of D/12 up to D each way (fine_slides) to where the image confirms the most of it
  // and sees through the least of it (agreeing pixels less those seen through): its end in view
  // where the image shows the tube ending. Kept only where it shows its ends no worse (pinned,
  // less twice those the tube goes on beyond) and sees as many of them ending: a pose slid until
  // its end met a drop would be pinned there (a held-out 12 mm arc: a pick 99 mm off). Only a
  // pose the image's checks accept is moved: moved, a pose they reject can pass them by a hair (a
  // straight tube and an arc on a real table-top frame without pipes, both handed out). On the
  // held-out zoos (tools/zoo --seed 20, 21) 4 of 9 wrong picks gone, 15 more top pipes found
  // (docs/zoo.md). Moved, the pose may be the same reading as its rival (an arc's rival slid 14
  // mm, the pose moved 10 mm towards it): the rival, no longer one, is dropped, else the two made
  // the pipe ambiguous (14-arc of seed 20: its bin stopped after 2 pipes, now 4). And only where
  // the image confirms the moved pose about as well (as_good): the pixel count can grow as a pose
  // slides more of itself into the view while a smaller share of it agrees (an arc 3 mm from its
  // pipe, agreeing 0.93, its end pinned under a pipe across, was moved 25 mm round itself to 0.88
  // and handed out while clearing 14-arc of seed 20). An end the moved pose shows ending but for
  // the sensor's shadow (its first probe unread, the second lower) counts as seen ending here: an
  // arc slid 19 mm past its end, over the stereo shadow the end casts on a pipe below it, read
  // both probes on that pipe and was kept there, a pick that took nothing (14-arc of seed 20, with
  // cores from 0.5 D^2). The moved pose's end stays pinned only, for all that follows.
  if (cfg.place_slides_finely && have_best && !lm.fine_slides.empty() && placed_by_ends(best.check) &&
      image_accepts(best.check, cfg) && !deadline.passed()) {
    const Pose found = best.model_to_bin;
    int most = confirmed_less_seen_through(best.check);
    const Pose* best_slide = nullptr;
    Verification best_slide_check;
    const auto t0 = Clock::now();
    for (const Pose& s : lm.fine_slides) {
      const Verification v = verify_at(ctx.bin_to_cam * (found * s));
      if (confirmed_less_seen_through(v) > most)
        most = confirmed_less_seen_through(v), best_slide = &s, best_slide_check = v;
    }
    if (best_slide) {
      PipeEstimate slid = slid_best(found, *best_slide, best_slide_check);
      read_ends_and_floor(&slid);
      if (turn_may_replace(slid.check, best.check) &&
          slid.check.ends_shown_ending() >= best.check.ends_seen_ending &&
          as_good(slid.check, best.check, cfg))
        moved_best_to(slid);
    }
    buf->times.verify_ms += ms_since(t0);
  }
  // Beyond the paper: the best polished. Of the hypotheses that are one reading, the image's
  // judgement took the one it confirms best, which does not tell a turn of 10-30 degrees about a
  // short pipe's length (a count of pixels within the tolerance); refined once more on all the
  // image shows of it, the pose settles where the points put it. Kept where the image confirms it
  // as well, shows its ends as well (as a turn: an end lost weakens the best against its rival,
  // and 20-3D's bin stopped with a pipe left) and it stays the same reading. Not for a pipe that
  // slides along itself: refined on all it explains, it slides (its slides are judged apart).
  if (cfg.polish_best && cfg.refine_on_explained && have_best && lm.slides.empty()) {
    const int n = explained_by_best();
    if (n > 0 && !deadline.passed()) {
      const PipeEstimate polished =
          refine_and_check(best.model_to_bin, best.ridge_cost_mm, buf->found_pts.data(), n);
      if (as_good(polished.check, best.check, cfg) && turn_may_replace(polished.check, best.check) &&
          !rivals(best, polished))
        best = polished;
    }
  }
  // Beyond the paper: a pose reaching out of the view, no tube read going on beyond its ends, is
  // placed by the shape of its part in view and the ends it pins; where another part of the pipe
  // has that shape (an S's other bend), the pipe may lie with that part there, the rest elsewhere
  // (judge_other_parts). Each such pose (other_parts_in_view) is refined on the region, kept
  // unrefined where the image judges that better, and judged; it never takes the best's place.
  // Where it is confirmed about as well on the pixels the sensor read (what lies where nothing is
  // read, as what lies out of the view, speaks for neither), its ends show no worse and the
  // pixels telling the two apart do not show the best (as a rival's), the pose is not known. A
  // 42 mm S, one bend in view, was handed out 152 mm off: another S's other bend lay there, its
  // rest in the view where the sensor read nothing (tools/zoo --seed 22, 11-S-asym). An end the
  // pose pins speaks for it: the other part must show its ends as well (a U with both legs out of
  // the view, its bend in view, or an arc, reads the same with another part there, and right
  // picks were lost: docs/experiments.md). An end the two share is read by the same probes and
  // speaks for neither: that S, its other bend on the bend in view and its end in view pinned,
  // was handed out turned end for end, 491 mm off. Another part at both ends of a pinned pose is
  // the pose moved less than the probes' reach, no other placement (judged so, a straight tube half
  // out of the view lost 11 of 90 picks; tools/zoo --seed 20, 01-straight). Judged on the
  // best as it stands here (slid, polished), and on a rival as good, which decide() may hand out
  // in its place: 42 % of a 934 mm Z out of the view, another stretch of it laid over its part in
  // view, was taken as the rival, never judged, 353 mm off (tools/zoo --seed 22, 13-Z, clearing).
  // The slides and the twins are judged above.
  bool cut_short = false;  // the deadline passed while another part was judged
  const auto other_part_unsure = [&](const PipeEstimate& found) {
    if (!(cfg.judge_other_parts && found.check.outside_view > 0 && found.check.ends_continued == 0 &&
          !deadline.passed()))
      return false;
    std::array<Pose, kMostOtherParts> motions;
    const int n = other_parts_in_view(lm.centreline_points, lm.centreline_step_mm, lm.tube_d_mm,
                                      std::max(lm.tube_d_mm, float(cfg.ambiguity_pose_mm)),
                                      kOtherPartRmsOfD * lm.tube_d_mm, found.model_to_cam, ctx.camera,
                                      &ctx.view, motions.data(), kMostOtherParts);
    for (int q = 0; q < n; ++q) {
      const Pose other = found.model_to_bin * motions[std::size_t(q)].inverse();
      bool known = pick_distance_mm(lm, other, found.model_to_bin, ambiguity_mm) <= ambiguity_mm;
      for (const Pose& half_turn : ctx.model.near_symmetries)  // a twin, judged above
        known = known ||
                pick_distance_mm(lm, other, found.model_to_bin * half_turn, ambiguity_mm) <= ambiguity_mm;
      if (known) continue;
      if (deadline.passed()) {
        cut_short = true;
        return false;
      }
      const PipeEstimate e =
          refine_and_check(other, found.ridge_cost_mm, buf->region_pts.data(), refine_count, true);
      if (pick_distance_mm(lm, e.model_to_bin, found.model_to_bin, ambiguity_mm) <= ambiguity_mm) continue;
      if (!as_good_where_read(e.check, found.check, cfg)) continue;
      if (!other_part_ends_no_worse(
              e.check, found.check,
              ends_shared(lm.centreline_points, lm.tube_d_mm, found.model_to_bin, e.model_to_bin)))
        continue;
      if (cfg.tell_rivals_apart) {
        const TellingPixels told = telling_pixels(found, e);
        if (pixels_show(told.for_a, told.for_b)) continue;  // the image shows the best, not the other
      }
      return true;
    }
    return false;
  };
  const bool rival_as_good = have_best && have_second && as_good(second.check, best.check, cfg);
  out.other_part_unsure = have_best && other_part_unsure(best);
  out.rival_other_part_unsure = rival_as_good && other_part_unsure(second);
  // A rival as good, which decide() may hand out in the best's place, is turned about its length
  // the same way (each turn refined, not weighed against the best): taken, it kept the best's
  // judgement before.
  for (std::size_t k = 0;
       cfg.judge_rolls && rival_as_good && k < lm.rolls.size() && !out.rival_roll_unsure && !cut_short; ++k) {
    if (deadline.passed()) {
      cut_short = true;
      break;
    }
    out.rival_roll_unsure =
        turn_as_good(second, refine_and_check(second.model_to_bin * lm.rolls[k], second.ridge_cost_mm,
                                              buf->region_pts.data(), refine_count, false));
  }
  if (cut_short) return out;
  // Beyond the paper: where the best and a rival about as good differ (a near twin's longer leg,
  // a slid pose's ends), which one the image shows (decide() weighs it with the ends).
  if (cfg.tell_rivals_apart && rival_as_good) out.told = telling_pixels(best, second);
  out.complete = true;
  return out;
}

bool work_candidate(const CandidateContext& ctx, const CandidateInput& in, const Deadline& deadline,
                    CandidateBuffers* buf, CandidateTrace* trace, PipeEstimate* estimate) {
  Evidence evidence;
  evidence.tube_d_mm = ctx.lm.tube_d_mm;
  evidence.extent_l_mm = ctx.lm.extent_l_mm;
  evidence.model_slides = !ctx.lm.slides.empty();
  evidence.model_straight = ctx.lm.slides_as_straight_tube();
  evidence.ends_must_pin = ctx.cfg.pin_slides_by_ends && evidence.model_slides;
  evidence.short_region = in.region->short_region;
  evidence.searched_again = in.searched_again;
  evidence.ends_judged = ctx.cfg.pin_slides_by_ends;
  evidence.has_ends = ctx.lm.centreline_points.size() >= 2;
  // Between two stages: decided by the evidence so far, or out of time. A candidate cut short
  // leaves no estimate (its outcome stays "budget").
  const auto settled = [&] {
    const Decision decision = decide(evidence, ctx.cfg);
    if (decision.decided) trace->outcome = decision.outcome;
    return decision.decided || deadline.passed();
  };

  trace->axis = find_axis(ctx, in, buf);
  if (settled()) return false;

  const ObservedRidge observed = observe_ridge(ctx, in, trace->axis, buf);
  trace->ridge_count = observed.count;
  evidence.reached = CandidateStage::observed_ridge;
  evidence.ridge_points = observed.count;
  if (settled()) return false;

  const RidgeFits fits = fit_ridges(ctx, in, trace->axis, observed, deadline, buf);
  if (!fits.complete) return false;
  trace->ridge_pose = fits.best_pose;
  trace->ridge_cost_mm = fits.best_cost_mm;
  for (const RidgeFit& f : buf->fits) trace->reached.add_fit(f.pose, f.cost_mm);
  evidence.reached = CandidateStage::ridge_fits;
  evidence.least_ridge_cost_mm = fits.least_cost_mm;
  if (settled()) return false;

  const Hypotheses judged = judge_hypotheses(ctx, in, observed, fits, deadline, buf, &trace->reached);
  if (!judged.complete) return false;
  evidence.reached = CandidateStage::hypotheses;
  evidence.have_best = judged.have_best, evidence.have_second = judged.have_second;
  evidence.best = judged.best.check, evidence.second = judged.second.check;
  evidence.told = judged.told;
  evidence.roll_unsure = judged.roll_unsure;
  evidence.rival_roll_unsure = judged.rival_roll_unsure;
  evidence.other_part_unsure = judged.other_part_unsure;
  evidence.rival_other_part_unsure = judged.rival_other_part_unsure;
  evidence.twin_unresolved = ctx.cfg.twin_beyond_resolution_ambiguous &&
                             (judged.best.model_to_cam * ctx.lm.centroid.cast<double>()).z() >
                                 twin_resolved_within_mm(*ctx.lm.model, ctx.camera.fx, kTwinUnresolvedPixels);
  evidence.rival_ends_apart =
      !judged.have_second || ends_tell_apart(ctx.lm.centreline_points, ctx.lm.tube_d_mm,
                                             judged.best.model_to_bin, judged.second.model_to_bin);
  const Decision decision = decide(evidence, ctx.cfg);
  const PipeEstimate& taken = decision.rival_taken ? judged.second : judged.best;
  trace->check = taken.check;
  trace->refined_to_cam = taken.model_to_cam;
  trace->outcome = decision.outcome;
  if (decision.outcome != CandidateOutcome::accepted) return false;
  *estimate = taken;
  estimate->ambiguous_why = decision.ambiguous_why;
  estimate->score = decision.score;
  estimate->pickable = decision.pickable;
  estimate->unresolved = decision.unresolved;
  estimate->withheld = decision.withheld;
  estimate->relief_sigmas = decision.relief_sigmas;
  estimate->searched_again = in.searched_again;
  return true;
}

}  // namespace pipeloc
