// decide(): every outcome a candidate's evidence can give, one row each, at the default config.
#include <gtest/gtest.h>

#include <cmath>

#include "locate/candidate.hpp"

namespace pipeloc {
namespace {

// A verification of 1000 model pixels (all judged for free space) with the given counts.
Verification seen(int agree_px, int free_space_px, int occluded_px) {
  Verification v;
  v.model_px = v.inner_px = 1000;
  v.agree_px = agree_px, v.free_space_px = v.inner_free_space_px = free_space_px, v.occluded_px = occluded_px;
  return v;
}

// ... of `model_px` pixels, `agree_px` of them agreeing.
Verification seen_on(int agree_px, int model_px) {
  Verification v;
  v.model_px = v.inner_px = model_px;
  v.agree_px = agree_px;
  return v;
}

constexpr float kD = 20;  // tube diameter (mm): R_th = 0.35 * 20 = 7 mm at the default config
constexpr float kL = 200;  // longest extent (mm): a ridge of 10 points is needed (short pipes: fewer)

// The same with its sides read: `level` of `side_px` side pixels lie at the silhouette's depth.
Verification with_sides(Verification v, int side_px, int level) {
  v.side_px = side_px, v.side_level_px = level;
  return v;
}

// `px` of its pixels without a reading (a sensor's shadow, a specular hole).
Verification unread(Verification v, int px) {
  v.unread_px = px;
  return v;
}

Verification outside_view(Verification v, float share) {
  v.outside_view = share;
  return v;
}

Verification below_floor(Verification v, float share) {
  v.below_floor = share;
  return v;
}

// A square of the silhouette, a quarter of the tube wide, seen through entirely.
Verification seen_through_patch(Verification v) {
  v.seen_through_patch = true;
  return v;
}

// A pipe that slides along itself, its ends judged: `pinned` shown ending, `continued` going on.
Evidence sliding(Evidence e, int pinned, int continued) {
  e.model_slides = e.ends_must_pin = true;
  e.best.ends_pinned = pinned, e.best.ends_continued = continued;
  return e;
}

// Of the best's pinned ends, `n` seen ending outright (the tip shown, every probe beyond read).
Evidence seen_ending(Evidence e, int n) {
  e.best.ends_seen_ending = n;
  return e;
}

// The best's part in the view slides along the pipe (judge_part_in_view).
Evidence slides_in_view(Evidence e) {
  e.best.part_in_view_slides = true;
  return e;
}

// ... a straight tube (its centreline on a line: LocatorModel::straight).
Evidence straight(Evidence e) {
  e.model_straight = true;
  return e;
}

// Of the best's pinned ends, `n` pinned by the probe read further along it alone (read_further).
Evidence pinned_further(Evidence e, int n) {
  e.best.ends_pinned_further = n;
  return e;
}

// Of the best's ends, `n` whose tip, or the way on just beyond it, lies outside the sensor's view:
// the image cannot show them.
Evidence ends_out_of_view(Evidence e, int n) {
  e.best.ends_out_of_view = n;
  return e;
}

// Ends read for the best and its rival (a model with a near twin): pinned and continued each.
Evidence ends_read(Evidence e, int best_pinned, int best_continued, int second_pinned, int second_continued) {
  e.ends_judged = true;
  e.best.ends_pinned = best_pinned, e.best.ends_continued = best_continued;
  e.second.ends_pinned = second_pinned, e.second.ends_continued = second_continued;
  return e;
}

// ... where the rival's ends lie within the first end probe's reach of the best's: both are read
// beyond the same ends of the pipe (ends_tell_apart).
Evidence ends_within_reach(Evidence e) {
  e.rival_ends_apart = false;
  return e;
}

// Another turn of the pipe about its own length confirmed as well, further than the pick's
// tolerance from the best (judge_rolls).
Evidence turn_unsure(Evidence e) {
  e.roll_unsure = true;
  return e;
}

// ... and so for the rival (which decide() may take in the best's place).
Evidence rival_turn_unsure(Evidence e) {
  e.rival_roll_unsure = true;
  return e;
}

// The best reaches out of the view, and a pose putting another part of the pipe where its part in
// view is seen is confirmed about as well on the pixels read (judge_other_parts).
Evidence other_part_unsure(Evidence e) {
  e.other_part_unsure = true;
  return e;
}

// ... and so for the rival (which decide() may take in the best's place).
Evidence rival_other_part_unsure(Evidence e) {
  e.rival_other_part_unsure = true;
  return e;
}

// Found by the second search of its region, on its whole top surface (retry_surface_cell_of_d).
Evidence searched_again(Evidence e) {
  e.searched_again = true;
  return e;
}

// Found from a region shorter than a * L (tried after the long ones).
Evidence from_short_region(Evidence e) {
  e.short_region = true;
  return e;
}

// The pixels where the best's and the rival's renders differ: `for_best` show the best, `for_rival`
// the rival.
Evidence told(Evidence e, int for_best, int for_rival) {
  e.told.for_a = for_best, e.told.for_b = for_rival;
  return e;
}

Evidence after_ridge(int ridge_points, float extent_l_mm = kL) {
  Evidence e;
  e.tube_d_mm = kD;
  e.extent_l_mm = extent_l_mm;
  e.reached = CandidateStage::observed_ridge;
  e.ridge_points = ridge_points;
  return e;
}

Evidence after_fits(float least_cost_mm) {
  Evidence e = after_ridge(40);
  e.reached = CandidateStage::ridge_fits;
  e.least_ridge_cost_mm = least_cost_mm;
  return e;
}

Evidence judged(Verification best) {
  Evidence e = after_fits(3);
  e.reached = CandidateStage::hypotheses;
  e.have_best = true;
  e.best = best;
  return e;
}

Evidence judged_with_rival(Verification best, Verification second) {
  Evidence e = judged(best);
  e.have_second = true;
  e.second = second;
  return e;
}

struct Row {
  const char* name;
  Evidence evidence;
  bool decided;
  CandidateOutcome outcome;
  bool ambiguous, pickable;
  float score;
  bool rival_taken = false;  // the rival, not the best, is judged and handed on
};

TEST(Decide, EveryOutcomeFromItsEvidence) {
  const Row rows[] = {
      // Not yet decided: nothing fails that the stages so far can answer.
      {"axis only", Evidence{}, false, CandidateOutcome::budget, false, false, 0},
      {"enough ridge points", after_ridge(kMinRidgePoints), false, CandidateOutcome::budget, false, false, 0},
      {"ridge fit within R_th", after_fits(6.9f), false, CandidateOutcome::budget, false, false, 0},
      // Rejected, at the first check that fails.
      {"few ridge points", after_ridge(kMinRidgePoints - 1), true, CandidateOutcome::few_ridge_points, false,
       false, 0},
      // A 25 mm elbow: 0.4 L is 5 cells of 2 mm.
      {"a short pipe's ridge", after_ridge(5, 25), false, CandidateOutcome::budget, false, false, 0},
      {"too few for a short pipe", after_ridge(4, 25), true, CandidateOutcome::few_ridge_points, false, false,
       0},
      // Above R_th but within residual_rescue_of_rth (1.5) of it: judged by the image instead.
      {"residual above R_th, within the rescue", after_fits(10.4f), false, CandidateOutcome::budget, false,
       false, 0},
      {"residual above the rescue", after_fits(10.6f), true, CandidateOutcome::residual_too_high, false,
       false, 0},
      {"agreement under 0.7", judged(seen(690, 0, 0)), true, CandidateOutcome::not_confirmed, false, false,
       0},
      {"free space over 0.05", judged(seen(900, 51, 0)), true, CandidateOutcome::not_confirmed, false, false,
       0},
      {"sides level: a smooth blob", judged(with_sides(seen(900, 0, 0), 100, 31)), true,
       CandidateOutcome::not_confirmed, false, false, 0},
      {"a third under the floor", judged(below_floor(seen(900, 0, 0), 0.31f)), true,
       CandidateOutcome::not_confirmed, false, false, 0},
      // Little free space in all, but in one place the sensor sees through a square of it.
      {"a square of it seen through", judged(seen_through_patch(seen(900, 10, 0))), true,
       CandidateOutcome::not_confirmed, false, false, 0},
      {"nothing judged",
       [] {
         Evidence e = judged(Verification{});
         e.have_best = false;
         return e;
       }(),
       true, CandidateOutcome::not_confirmed, false, false, 0},
      // Accepted: score = agreement * (1 - occluded) * (1 - out of view), halved when ambiguous:
      // the share of the whole pipe the image confirms.
      {"accepted and pickable", judged(seen(900, 10, 100)), true, CandidateOutcome::accepted, false, true,
       0.81f},
      {"sides drop away", judged(with_sides(seen(900, 0, 0), 100, 29)), true, CandidateOutcome::accepted,
       false, true, 0.9f},
      // Few side pixels read: the level ones counted out of kMinSidePx.
      {"few side pixels, few of them level", judged(with_sides(seen(900, 0, 0), kMinSidePx - 1, 6)), true,
       CandidateOutcome::accepted, false, true, 0.9f},
      {"few side pixels, nearly all level", judged(with_sides(seen(900, 0, 0), 14, 13)), true,
       CandidateOutcome::not_confirmed, false, false, 0},
      {"resting on the floor", judged(below_floor(seen(900, 0, 0), 0.29f)), true, CandidateOutcome::accepted,
       false, true, 0.9f},
      {"accepted under another pipe", judged(seen(800, 0, 200)), true, CandidateOutcome::accepted, false,
       false, 0.64f},
      // Found by the second search of a region: reported; handed out (where the first searches
      // hand out none: LocateOutput::pick()) only where the image confirms 0.9 of what is in view
      // and its sides are read dropping away.
      {"searched again, its sides not read", searched_again(judged(seen(1000, 0, 0))), true,
       CandidateOutcome::accepted, false, false, 1.0f},
      {"searched again, well seen, sides dropping away", searched_again(judged(with_sides(seen(950, 0, 0), 100, 10))),
       true, CandidateOutcome::accepted, false, true, 0.95f},
      {"searched again, agreeing under 0.9", searched_again(judged(with_sides(seen(890, 0, 0), 100, 10))), true,
       CandidateOutcome::accepted, false, false, 0.89f},
      {"searched again, too few side pixels to judge",
       searched_again(judged(with_sides(seen(950, 0, 0), kMinSidePx - 1, 0))), true, CandidateOutcome::accepted,
       false, false, 0.95f},
      // ... of what is in view and not under something in front (at most verify_max_occluded).
      {"searched again, a tenth under another, 0.9 of the rest",
       searched_again(judged(with_sides(seen(820, 0, 100), 100, 10))), true, CandidateOutcome::accepted, false,
       true, 0.82f * 0.9f},
      {"searched again, a tenth under another, 0.85 of the rest",
       searched_again(judged(with_sides(seen(765, 0, 100), 100, 10))), true, CandidateOutcome::accepted, false,
       false, 0.765f * 0.9f},
      {"searched again, 0.9 of what is in view, a fifth out of it",
       searched_again(judged(with_sides(outside_view(seen(950, 0, 0), 0.2f), 100, 10))), true,
       CandidateOutcome::accepted, false, true, 0.76f},
      // A pose both its ends are seen ending (the tip shown, every probe beyond read and lower) is
      // confirmed on the pixels the sensor read, at least verify_min_read_share (half) of them
      // counted; the score still counts the unread ones as not confirmed.
      {"a third not read, both ends seen ending, what was read confirmed",
       seen_ending(ends_read(judged(unread(seen(650, 0, 0), 350)), 2, 0, 0, 0), 2), true,
       CandidateOutcome::accepted, false, true, 0.65f},
      {"the same, one end seen ending", seen_ending(ends_read(judged(unread(seen(650, 0, 0), 350)), 2, 0, 0, 0), 1),
       true, CandidateOutcome::not_confirmed, false, false, 0},
      {"the same, both ends pinned, neither seen ending", ends_read(judged(unread(seen(650, 0, 0), 350)), 2, 0, 0, 0),
       true, CandidateOutcome::not_confirmed, false, false, 0},
      {"seven tenths not read: half counted",
       seen_ending(ends_read(judged(unread(seen(300, 0, 0), 700)), 2, 0, 0, 0), 2), true,
       CandidateOutcome::not_confirmed, false, false, 0},
      // Out of the view the image checks nothing: that part counts as not confirmed, and the
      // image must still confirm verify_min_agreement of the whole pipe.
      {"a fifth out of the view, the rest confirmed", judged(outside_view(seen(900, 0, 0), 0.2f)), true,
       CandidateOutcome::accepted, false, true, 0.72f},
      {"a fifth out of the view, too little confirmed", judged(outside_view(seen(800, 0, 0), 0.2f)), true,
       CandidateOutcome::accepted, false, false, 0.64f},
      {"a third out of the view", judged(outside_view(seen(850, 0, 0), 0.35f)), true,
       CandidateOutcome::accepted, false, false, 0.5525f},
      // Up to half out of the view where what is in view agrees 0.9, and, where the ends are
      // read, an end is pinned.
      {"a third out of the view, what is in view well seen", judged(outside_view(seen(950, 0, 0), 0.35f)),
       true, CandidateOutcome::accepted, false, true, 0.6175f},
      // ... of what is in view and not under something in front (at most verify_max_occluded).
      {"a third out of the view, 7 % under another, the rest well seen",
       ends_read(judged(outside_view(seen(880, 0, 70), 0.35f)), 1, 0, 0, 0), true, CandidateOutcome::accepted,
       false, true, 0.88f * 0.93f * 0.65f},
      {"the same, nothing in front: what is in view not well seen",
       ends_read(judged(outside_view(unread(seen(880, 0, 0), 70), 0.35f)), 1, 0, 0, 0), true,
       CandidateOutcome::accepted, false, false, 0.88f * 0.65f},
      {"a third out of the view, a sixth under another", judged(outside_view(seen(840, 0, 160), 0.35f)), true,
       CandidateOutcome::accepted, false, false, 0.84f * 0.84f * 0.65f},
      // ... where a pipe that slides along itself shows an end seen ending outright, not pinned
      // past a hidden tip (what is in view well seen counting what lies in front: the old rule).
      {"a third out of the view, 7 % under another, sliding, an end seen ending",
       seen_ending(sliding(ends_read(judged(outside_view(seen(880, 0, 70), 0.35f)), 1, 0, 0, 0), 1, 0), 1), true,
       CandidateOutcome::accepted, false, true, 0.88f * 0.93f * 0.65f},
      {"the same, its end pinned past a hidden tip",
       sliding(ends_read(judged(outside_view(seen(880, 0, 70), 0.35f)), 1, 0, 0, 0), 1, 0), true,
       CandidateOutcome::accepted, false, false, 0.88f * 0.93f * 0.65f},
      {"a third out of the view, well seen, sliding, its end pinned past a hidden tip",
       sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0), true,
       CandidateOutcome::accepted, false, true, 0.6175f},
      {"six tenths out of the view", judged(outside_view(seen(1000, 0, 0), 0.6f)), true,
       CandidateOutcome::accepted, false, false, 0.4f},
      {"a third out of the view, ends read, none pinned",
       ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 0, 0, 0, 0), true, CandidateOutcome::accepted,
       false, false, 0.6175f},
      {"a third out of the view, ends read, one pinned",
       ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), true, CandidateOutcome::accepted,
       false, true, 0.6175f},
      // ... unless both ends lie out of the view, where no image shows them: the bends in view
      // place a pipe that does not slide along itself.
      {"a third out of the view, well seen, both ends out of it",
       ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 0, 0, 0, 0), 2), true,
       CandidateOutcome::accepted, false, true, 0.6175f},
      // ... or one end out of it and the other neither pinned nor going on: it shows no more
      // than an end out of the view (end_unread_as_out_of_view) ...
      {"the same, one end out of it, the other neither pinned nor going on",
       ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 0, 0, 0, 0), 1), true,
       CandidateOutcome::accepted, false, true, 0.6175f},
      // ... but not where the tube goes on beyond the end in view, nor for a pipe that slides.
      {"the same, the tube going on beyond the end in view",
       ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 0, 1, 0, 0), 1), true,
       CandidateOutcome::accepted, false, false, 0.6175f},
      {"the same, the end in view neither pinned nor going on, a pipe that slides",
       ends_out_of_view(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 0, 0, 0, 0), 0, 0), 1),
       true, CandidateOutcome::accepted, true, false, 0.6175f * kAmbiguousScoreFactor},
      {"the same, both ends out of it, what is in view not well seen",
       ends_out_of_view(ends_read(judged(outside_view(seen(880, 0, 0), 0.35f)), 0, 0, 0, 0), 2), true,
       CandidateOutcome::accepted, false, false, 0.572f},
      // ... but where its part in view slides along the pipe (an arc's or a coil's loop), only an
      // end in view seen ending outright, none going on, places it (pin_part_in_view_by_ends).
      {"a third out of the view, well seen, both ends out of it, its part in view sliding",
       slides_in_view(
           ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 0, 0, 0, 0), 2)),
       true, CandidateOutcome::accepted, true, false, 0.6175f * kAmbiguousScoreFactor},
      {"the same, one end in view pinned, not seen ending outright",
       slides_in_view(
           ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1)),
       true, CandidateOutcome::accepted, true, false, 0.6175f * kAmbiguousScoreFactor},
      {"the same, that end seen ending outright",
       seen_ending(slides_in_view(ends_out_of_view(
                       ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1)),
                   1),
       true, CandidateOutcome::accepted, false, true, 0.6175f},
      // From a region shorter than a * L only for a pipe that does not slide along itself, its
      // ends read and one pinned: where a sliding pipe lies along what is out of the view, a short
      // piece of its top does not say.
      {"a third out of the view, well seen, from a short region, one end pinned",
       from_short_region(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0)), true,
       CandidateOutcome::accepted, false, true, 0.6175f},
      {"the same, its ends not read", from_short_region(judged(outside_view(seen(950, 0, 0), 0.35f))), true,
       CandidateOutcome::accepted, false, false, 0.6175f},
      {"the same, a pipe sliding along itself",
       from_short_region(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0)),
       true, CandidateOutcome::accepted, false, false, 0.6175f},
      // ... unless both its ends are seen ending outright, none going on: a long arc whose middle
      // runs out of the view is placed by them.
      {"the same, sliding, both ends seen ending outright",
       seen_ending(
           from_short_region(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 2, 0, 0, 0), 2, 0)), 2),
       true, CandidateOutcome::accepted, false, true, 0.6175f},
      {"the same, sliding, one of its two pinned ends seen ending outright",
       seen_ending(
           from_short_region(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 2, 0, 0, 0), 2, 0)), 1),
       true, CandidateOutcome::accepted, false, false, 0.6175f},
      // ... and a straight tube by its ends in view, at least one, each seen ending outright: one
      // running out of the view at its other end.
      {"the same, a straight tube, its one end in view seen ending outright",
       straight(ends_out_of_view(
           seen_ending(
               from_short_region(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0)),
               1),
           1)),
       true, CandidateOutcome::accepted, false, true, 0.6175f},
      {"the same, an arc",
       ends_out_of_view(
           seen_ending(
               from_short_region(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0)),
               1),
           1),
       true, CandidateOutcome::accepted, false, true, 0.6175f},
      {"the same, an arc, its end in view pinned past a hidden tip",
       ends_out_of_view(
           from_short_region(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0)), 1),
       true, CandidateOutcome::accepted, false, false, 0.6175f},
      {"the same, a straight tube, both ends in view, one seen ending outright",
       straight(seen_ending(
           from_short_region(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 2, 0, 0, 0), 2, 0)), 1)),
       true, CandidateOutcome::accepted, false, false, 0.6175f},
      // A straight tube reaching beyond verify_max_outside_view is placed only by an end pinned by
      // the probes beside its tip: past the sensor's shadow, the probe read further along it may
      // lie beyond its end.
      {"a third out of the view, sliding, its end in view pinned",
       ends_out_of_view(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0), 1),
       true, CandidateOutcome::accepted, false, true, 0.6175f},
      {"the same, a straight tube pinned by the probe read further alone",
       straight(pinned_further(
           ends_out_of_view(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0), 1),
           1)),
       true, CandidateOutcome::accepted, false, false, 0.6175f},
      {"the same, an arc pinned by the probe read further alone",
       pinned_further(
           ends_out_of_view(sliding(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 1, 0, 0, 0), 1, 0), 1),
           1),
       true, CandidateOutcome::accepted, false, true, 0.6175f},
      {"a fifth out of the view, the rest confirmed, from a short region",
       from_short_region(judged(outside_view(seen(900, 0, 0), 0.2f))), true, CandidateOutcome::accepted,
       false, true, 0.72f},
      // The tube going on beyond both ends: the pipe there is longer than the pose.
      {"ends read, the tube going on beyond both", ends_read(judged(seen(900, 0, 0)), 0, 2, 0, 0), true,
       CandidateOutcome::accepted, false, false, 0.9f},
      // A pipe that does not slide, wholly in the view, its ends read and neither shown ending:
      // the image does not place it (a pipe model over a hose or a box's edge). Reaching out of
      // the view, an end may lie beyond it; sliding pipes have their own rule (below).
      {"ends read, none pinned, wholly in view", ends_read(judged(seen(900, 0, 0)), 0, 0, 0, 0), true,
       CandidateOutcome::accepted, false, false, 0.9f},
      {"the same, a model without a centreline (its ends never read)",
       [] {
         Evidence e = ends_read(judged(seen(900, 0, 0)), 0, 0, 0, 0);
         e.has_ends = false;
         return e;
       }(),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      {"ends read, none pinned, a twentieth out of the view at one end",
       ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.05f)), 0, 0, 0, 0), 1), true,
       CandidateOutcome::accepted, false, true, 0.9025f},
      // Going on beyond one end, wholly in view: placed only where the other is seen ending outright
      // (a thin U laid across two pipes pins an end past a hidden tip).
      {"ends read, going on beyond one, the other seen ending",
       seen_ending(ends_read(judged(seen(900, 0, 0)), 1, 1, 0, 0), 1), true, CandidateOutcome::accepted, false,
       true, 0.9f},
      {"ends read, going on beyond one, the other pinned but not seen ending",
       ends_read(judged(seen(900, 0, 0)), 1, 1, 0, 0), true, CandidateOutcome::accepted, false, false, 0.9f},
      {"the same, a twentieth of its middle out of the view",
       ends_read(judged(outside_view(seen(950, 0, 0), 0.05f)), 1, 1, 0, 0), true, CandidateOutcome::accepted, false,
       false, 0.9025f},
      {"a tenth under a pipe, a tenth out of the view", judged(outside_view(seen(900, 0, 100), 0.1f)), true,
       CandidateOutcome::accepted, false, true, 0.729f},
      {"a twentieth out of the view", judged(outside_view(seen(900, 0, 0), 0.05f)), true,
       CandidateOutcome::accepted, false, true, 0.855f},
      {"rival about as good: ambiguous", judged_with_rival(seen(900, 0, 0), seen(860, 0, 0)), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      {"rival failing by a hair: still ambiguous", judged_with_rival(seen(700, 0, 0), seen(690, 0, 0)), true,
       CandidateOutcome::accepted, true, false, 0.35f},
      // Ambiguous and more than verify_max_outside_view_well_seen (half) out of the view: the
      // image places neither pose, so it is no estimate.
      {"rival as good, four tenths out of the view",
       judged_with_rival(outside_view(seen(900, 0, 0), 0.4f), seen(860, 0, 0)), true,
       CandidateOutcome::accepted, true, false, 0.27f},
      {"rival as good, six tenths out of the view",
       judged_with_rival(outside_view(seen(900, 0, 0), 0.6f), seen(860, 0, 0)), true,
       CandidateOutcome::not_confirmed, true, false, 0},
      {"sliding, no end seen, six tenths out of the view",
       sliding(judged(outside_view(seen(900, 0, 0), 0.6f)), 0, 0), true, CandidateOutcome::not_confirmed,
       true, false, 0},
      // A near twin as good where the image shows the best's ends, and the tube going on beyond
      // one of the twin's: not ambiguous. Ends seen for neither: ambiguous.
      {"twin as good, its end goes on",
       ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 2, 0, 1, 1), true,
       CandidateOutcome::accepted, false, true, 0.9f},
      {"twin as good, no end seen",
       ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 0, 0, 0, 0), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // ... but not where the twin's ends lie within the probes' reach of the best's: what the
      // probes read there speaks for neither. The pixels telling them apart still may.
      {"twin as good, its end goes on, its ends within reach of the best's",
       ends_within_reach(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 2, 0, 1, 1)), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      {"twin as good, ends within reach, the pixels telling them apart show the best",
       told(ends_within_reach(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 2, 0, 1, 1)),
            kMinTellingPx, 0),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      // Where the two differ, the image shows the best and hardly the rival: not ambiguous.
      {"twin as good, the pixels telling them apart show the best",
       told(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), kMinTellingPx,
            kMinTellingPx / kTellingRatio),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      {"twin as good, too few pixels tell them apart",
       told(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), kMinTellingPx - 1, 0), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      {"twin as good, the pixels telling them apart show both",
       told(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 100, 100 / kTellingRatio + 1), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // The twin's end reads as going on, but where the two differ the pixels speak for the twin
      // half as much as for the best: another pipe may touch the right pose's end. Ambiguous.
      {"twin's end goes on, one end each pinned",
       ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 1, 1), true,
       CandidateOutcome::accepted, false, true, 0.9f},
      {"twin's end goes on, the pixels speak for it too",
       told(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 1, 1), 28, 18), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // A rival about as good whose ends the image shows better is the pipe (rival_taken): the
      // best by a hair with no end seen, or with the tube going on beyond one of its ends.
      {"rival as good, the image pins its end and not the best's",
       ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 0, 0, 1, 0), true,
       CandidateOutcome::accepted, false, true, 0.88f, true},
      {"rival as good, the tube goes on beyond the best's end",
       ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 1, 1, 0), true,
       CandidateOutcome::accepted, false, true, 0.88f, true},
      {"rival as good, the image pins its end and not the best's, within reach of them",
       ends_within_reach(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 0, 0, 1, 0)), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // ... or whose ends it shows as well where, of the pixels telling the two apart, it shows
      // the rival and hardly the best (a Z's twin with its legs swapped, one end out of the view).
      {"rival as good, the pixels telling them apart show the rival",
       told(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 1, 0), 0, kMinTellingPx),
       true, CandidateOutcome::accepted, false, true, 0.88f, true},
      {"the pixels show the rival, but the image pins the best's end and not the rival's",
       told(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 0, 0), 0, kMinTellingPx),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      {"the pixels show both",
       told(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 1, 0),
            kMinTellingPx / kTellingRatio + 1, kMinTellingPx),
       true, CandidateOutcome::accepted, true, false, 0.45f},
      {"the pixels show the rival, the best's ends pinned within reach of the rival's",
       told(ends_within_reach(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 2, 0, 1, 0)), 0,
            kMinTellingPx),
       true, CandidateOutcome::accepted, false, true, 0.88f, true},
      {"rival as good, its end pinned, but under the floor",
       ends_read(judged_with_rival(seen(900, 0, 0), below_floor(seen(880, 0, 0), 0.31f)), 0, 0, 1, 0), true,
       CandidateOutcome::not_confirmed, false, false, 0, true},
      {"rival clearly worse", judged_with_rival(seen(900, 0, 0), seen(840, 0, 0)), true,
       CandidateOutcome::accepted, false, true, 0.9f},
      // Worse only by its part under a pipe in front (a Z's twin, its longer leg under a crossing
      // pipe): as good where the sensor saw either, so ambiguous; worse there too, not.
      {"rival worse only where a pipe lies in front of it", judged_with_rival(seen(900, 0, 0), seen(840, 0, 60)),
       true, CandidateOutcome::accepted, true, false, 0.45f},
      {"rival worse where nothing lies in front of it too", judged_with_rival(seen(900, 0, 0), seen(780, 0, 60)),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      {"rival worse only where a pipe lies in front of it, the best's end pinned",
       ends_read(judged_with_rival(seen(900, 0, 0), seen(840, 0, 60)), 1, 0, 0, 0), true,
       CandidateOutcome::accepted, false, true, 0.9f},
      // ... but 0.06 worse on a pipe of 150 pixels is within two standard errors of the agreement.
      {"rival 0.06 worse on 150 pixels", judged_with_rival(seen_on(135, 150), seen_on(126, 150)), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // A turn about its own length the image does not tell apart: not known to the pick's tolerance.
      {"its turn about its length not told", turn_unsure(judged(seen(900, 0, 0))), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // Another part of the pipe could be the part in view (an S's other bend): not placed.
      {"another part of it as well in view", other_part_unsure(judged(seen(900, 0, 0))), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // A pipe that slides along itself (an arc, a coil, a straight run) is placed by its ends.
      {"sliding, an end pinned", sliding(judged(seen(900, 0, 0)), 1, 0), true, CandidateOutcome::accepted,
       false, true, 0.9f},
      {"sliding, no end seen", sliding(judged(seen(900, 0, 0)), 0, 0), true, CandidateOutcome::accepted, true,
       false, 0.45f},
      {"sliding, the tube goes on beyond an end", sliding(judged(seen(900, 0, 0)), 1, 1), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // ... and a slid rival pinned where the best is not does not take its place (a slid coil's
      // end stopping short of a pipe in front reads as pinned): ambiguous.
      {"sliding, a slid rival as good pinned",
       sliding(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 0, 0, 1, 0), 0, 0), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // A sliding pipe's end pinned tells it from a slid rival as good only where the image shows it
      // ending outright; a pin read past a hidden tip or on one probe does not.
      {"sliding, an end seen ending, a slid rival as good with none seen",
       seen_ending(sliding(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 0, 0), 1, 0), 1),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      {"sliding, an end seen ending, a slid rival as good within reach of its ends",
       ends_within_reach(seen_ending(
           sliding(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 0, 0), 1, 0), 1)),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      {"sliding, an end pinned past a hidden tip, a slid rival as good",
       sliding(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 0, 0), 1, 0), true,
       CandidateOutcome::accepted, true, false, 0.45f},
      // ... nor do the pixels telling the two apart, but for a straight tube whose ends place it no
      // worse than the rival's: an end seen ending outright, none going on.
      {"sliding, both an end seen ending, the pixels show the best",
       told(seen_ending(sliding(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 1, 0), 1, 0),
                        1),
            kMinTellingPx, 0),
       true, CandidateOutcome::accepted, true, false, 0.45f},
      {"the same, a straight tube",
       straight(told(
           seen_ending(sliding(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 1, 0), 1, 0), 1),
           kMinTellingPx, 0)),
       true, CandidateOutcome::accepted, false, true, 0.9f},
      {"the same, a straight tube, its end pinned past a hidden tip",
       straight(told(sliding(ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 1, 0, 1, 0), 1, 0),
                     kMinTellingPx, 0)),
       true, CandidateOutcome::accepted, true, false, 0.45f},
      {"rival seen through: worse", judged_with_rival(seen(900, 0, 0), seen(900, 30, 0)), true,
       CandidateOutcome::accepted, false, true, 0.9f},
  };
  const LocateConfig cfg;
  for (const Row& row : rows) {
    SCOPED_TRACE(row.name);
    const Decision d = decide(row.evidence, cfg);
    EXPECT_EQ(d.decided, row.decided);
    if (!row.decided) continue;
    EXPECT_STREQ(outcome_name(d.outcome), outcome_name(row.outcome));
    EXPECT_EQ(d.ambiguous(), row.ambiguous);
    EXPECT_EQ(d.pickable, row.pickable);
    EXPECT_NEAR(d.score, row.score, 1e-5f);
    EXPECT_EQ(d.rival_taken, row.rival_taken);
  }
}

// A rival taken in the best's place (its end pinned, the best's not) is judged as the best is, by
// its own judgement: ambiguous (`why`) where its own judgement says so (rival_unsure), not where
// only the best's does (best_unsure); the best kept, by the best's.
void expect_a_rival_taken_judged_by_its_own(Evidence (*best_unsure)(Evidence),
                                            Evidence (*rival_unsure)(Evidence), unsigned why) {
  const LocateConfig cfg;
  const Evidence rival_pinned = ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 0, 0, 1, 0);
  Decision d = decide(rival_unsure(rival_pinned), cfg);
  EXPECT_TRUE(d.rival_taken);
  EXPECT_EQ(d.ambiguous_why, why);
  EXPECT_FALSE(d.pickable);
  d = decide(best_unsure(rival_pinned), cfg);
  EXPECT_TRUE(d.rival_taken);
  EXPECT_FALSE(d.ambiguous());
  EXPECT_TRUE(d.pickable);
  EXPECT_NEAR(d.score, 0.88f, 1e-5f);
  // The best kept (its ends pinned, the tube going on beyond the rival's).
  const Evidence best_pinned = ends_read(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 2, 0, 1, 1);
  d = decide(rival_unsure(best_pinned), cfg);
  EXPECT_FALSE(d.rival_taken);
  EXPECT_FALSE(d.ambiguous());
  EXPECT_TRUE(d.pickable);
  d = decide(best_unsure(best_pinned), cfg);
  EXPECT_FALSE(d.rival_taken);
  EXPECT_EQ(d.ambiguous_why, why);
}

// ... for another part of the pipe in view: a Z 42 % out of the view, another stretch of it laid
// over its part in view, was taken as the rival, 353 mm off (judge_other_parts).
TEST(Decide, ARivalTakenIsJudgedForAnotherPartByItsOwnJudgement) {
  expect_a_rival_taken_judged_by_its_own(other_part_unsure, rival_other_part_unsure, kAmbiguousOtherPart);
}

// ... and for its turn about its length (judge_rolls).
TEST(Decide, ARivalTakenIsJudgedForItsTurnByItsOwnJudgement) {
  expect_a_rival_taken_judged_by_its_own(turn_unsure, rival_turn_unsure, kAmbiguousRoll);
}

// An ambiguous pose says why, a reason for each rule that made it so; a pose not ambiguous, none.
TEST(Decide, AnAmbiguousPoseSaysWhy) {
  const LocateConfig cfg;
  Evidence twin_far = judged(seen(900, 0, 0));
  twin_far.twin_unresolved = true;
  const struct {
    const char* name;
    Evidence evidence;
    unsigned why;
  } rows[] = {
      {"a pose alone", judged(seen(900, 0, 0)), 0u},
      {"a rival as good", judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), kAmbiguousRival},
      {"sliding, no end seen", sliding(judged(seen(900, 0, 0)), 0, 0), kAmbiguousSlides},
      {"its turn about its length not told", turn_unsure(judged(seen(900, 0, 0))), kAmbiguousRoll},
      {"another part of it as well in view", other_part_unsure(judged(seen(900, 0, 0))), kAmbiguousOtherPart},
      {"its near twin beyond the view's resolution", twin_far, kAmbiguousTwinUnresolved},
      {"a rival as good and its turn not told",
       turn_unsure(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0))), kAmbiguousRival | kAmbiguousRoll},
  };
  for (const auto& row : rows) {
    SCOPED_TRACE(row.name);
    const Decision d = decide(row.evidence, cfg);
    EXPECT_EQ(d.ambiguous_why, row.why);
    EXPECT_EQ(d.ambiguous(), row.why != 0);
  }
  EXPECT_STREQ(ambiguity_name(ambiguity_index(kAmbiguousTwinUnresolved)), "twin_unresolved");
  EXPECT_STREQ(ambiguity_label(ambiguity_index(kAmbiguousOtherPart)), "OTHER PART");
}

// The checks follow the config's thresholds, not fixed numbers.
TEST(Decide, ThresholdsComeFromTheConfig) {
  LocateConfig cfg;
  cfg.residual_max_of_d = 0.5;  // R_th = 10 mm, 15 mm with the rescue
  EXPECT_FALSE(decide(after_fits(14), cfg).decided);
  cfg.residual_rescue_of_rth = 1;  // the paper's hard cut
  EXPECT_TRUE(decide(after_fits(10.5f), cfg).decided);
  cfg.verify_min_agreement = 0.6;
  EXPECT_EQ(decide(judged(seen(650, 0, 0)), cfg).outcome, CandidateOutcome::accepted);
  cfg.verify_max_occluded = 0.3;
  EXPECT_TRUE(decide(judged(seen(800, 0, 200)), cfg).pickable);
  EXPECT_TRUE(decide(judged(outside_view(seen(950, 0, 0), 0.45f)), cfg).pickable);  // well seen
  const Evidence one_end_out =
      ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.35f)), 0, 0, 0, 0), 1);
  EXPECT_TRUE(decide(one_end_out, cfg).pickable);
  cfg.end_unread_as_out_of_view = false;  // off: the end in view must be pinned
  EXPECT_FALSE(decide(one_end_out, cfg).pickable);
  cfg.verify_max_outside_view_well_seen = 0.4;
  EXPECT_FALSE(decide(judged(outside_view(seen(950, 0, 0), 0.45f)), cfg).pickable);
  cfg.verify_max_outside_view_well_seen = 0;  // off: the first rule alone
  EXPECT_FALSE(decide(judged(outside_view(seen(1000, 0, 0), 0.35f)), cfg).pickable);
  cfg.verify_max_outside_view = 0.4;
  EXPECT_TRUE(decide(judged(outside_view(seen(1000, 0, 0), 0.35f)), cfg).pickable);
  const Evidence told_apart = told(judged_with_rival(seen(900, 0, 0), seen(880, 0, 0)), 100, 0);
  EXPECT_FALSE(decide(told_apart, cfg).ambiguous());
  cfg.tell_rivals_apart = false;
  EXPECT_TRUE(decide(told_apart, cfg).ambiguous());
  const Evidence rival_under_a_pipe = judged_with_rival(seen(900, 0, 0), seen(840, 0, 60));
  EXPECT_TRUE(decide(rival_under_a_pipe, cfg).ambiguous());
  cfg.rivals_judged_where_seen = false;  // off: its part under a pipe counts against it
  EXPECT_FALSE(decide(rival_under_a_pipe, cfg).ambiguous());
  cfg.ambiguity_quality_margin = 0.01;
  EXPECT_FALSE(decide(judged_with_rival(seen(900, 0, 0), seen(860, 0, 0)), cfg).ambiguous());
  const Evidence half_read = seen_ending(ends_read(judged(unread(seen(450, 0, 0), 550)), 2, 0, 0, 0), 2);
  EXPECT_EQ(decide(half_read, cfg).outcome, CandidateOutcome::accepted);  // 450 of 500 counted
  cfg.verify_min_read_share = 1;  // off: unread pixels count against the pose
  EXPECT_EQ(decide(half_read, cfg).outcome, CandidateOutcome::not_confirmed);
  const Evidence again = searched_again(judged(with_sides(seen(950, 0, 0), 100, 10)));
  EXPECT_TRUE(decide(again, cfg).pickable);
  cfg.second_search_may_pick = false;  // off: the second searches' poses are never handed out
  EXPECT_FALSE(decide(again, cfg).pickable);
}

// Up to verify_max_outside_view_ends_seen (three quarters) of a pipe that does not slide along
// itself may lie out of the view where both its ends in view are seen ending outright, the tube
// going on beyond neither, and what is in view agrees verify_well_seen_agreement: a U whose bend
// runs out of the view. One end seen, the other out of the view, stays "part seen" beyond half.
TEST(Decide, APipeShowingBothEndsEndingMayReachFurtherOutOfTheView) {
  LocateConfig cfg;
  // `share` out of the view, from a short region, `pinned` ends pinned, `seen_end` seen ending outright.
  const auto out_of_view = [](float share, int pinned, int seen_end) {
    return from_short_region(
        seen_ending(ends_read(judged(outside_view(seen(950, 0, 0), share)), pinned, 0, 0, 0), seen_end));
  };
  EXPECT_TRUE(decide(out_of_view(0.65f, 2, 2), cfg).pickable);
  EXPECT_TRUE(decide(out_of_view(0.75f, 2, 2), cfg).pickable);
  const auto withheld_part_seen = [&](const Evidence& e) {
    const Decision d = decide(e, cfg);
    return !d.pickable && (d.withheld & kWithheldPartSeen) != 0;
  };
  EXPECT_TRUE(withheld_part_seen(out_of_view(0.8f, 2, 2)));                        // further out
  EXPECT_TRUE(withheld_part_seen(ends_out_of_view(out_of_view(0.65f, 1, 1), 1)));  // one end seen
  EXPECT_TRUE(withheld_part_seen(out_of_view(0.65f, 2, 1)));                       // one pinned past its tip
  EXPECT_TRUE(withheld_part_seen(slides_in_view(out_of_view(0.65f, 2, 2))));       // its part in view slides
  Evidence less_agreeing = out_of_view(0.65f, 2, 2);
  less_agreeing.best.agree_px = 850;  // 0.85 of what is in view: not well seen
  EXPECT_TRUE(withheld_part_seen(less_agreeing));
  cfg.verify_max_outside_view_ends_seen = 0.5;  // no further than the well-seen rule
  EXPECT_TRUE(withheld_part_seen(out_of_view(0.65f, 2, 2)));
  LocateConfig paper;
  use_paper_search(&paper);  // the paper's pipeline: off
  EXPECT_NE(decide(out_of_view(0.65f, 2, 2), paper).withheld & kWithheldPartSeen, 0u);
}

// A pipe that does not slide along itself is placed only where the image shows one of its ends
// (pinned, the tube going on beyond neither). Whether it lies wholly in the view is read at its
// ends: with both in the view, a part of its middle out of it does not excuse them; with one out
// of the view, the bends in view may place it.
TEST(Decide, APipeWithBothEndsInTheViewIsPlacedOnlyByOneShown) {
  LocateConfig cfg;
  const auto middle_out = [](int ends_out, int pinned, int continued) {
    return ends_out_of_view(ends_read(judged(outside_view(seen(950, 0, 0), 0.05f)), pinned, continued, 0, 0),
                            ends_out);
  };
  const auto withheld_no_end = [&](const Evidence& e, const LocateConfig& c) {
    return (decide(e, c).withheld & kWithheldNoEnd) != 0;
  };
  EXPECT_TRUE(withheld_no_end(middle_out(0, 0, 0), cfg));   // both ends in view, neither shown
  EXPECT_TRUE(withheld_no_end(middle_out(0, 1, 1), cfg));   // one pinned, the tube going on beyond the other
  EXPECT_FALSE(withheld_no_end(middle_out(0, 1, 0), cfg));  // one pinned
  EXPECT_FALSE(withheld_no_end(middle_out(1, 0, 0), cfg));  // one end out of the view
  EXPECT_TRUE(decide(middle_out(0, 1, 0), cfg).pickable);
  cfg.end_shown_where_both_in_view = false;  // off: any part out of the view excuses the ends
  EXPECT_FALSE(withheld_no_end(middle_out(0, 0, 0), cfg));
  LocateConfig paper;
  use_paper_search(&paper);  // the paper's pipeline: off
  EXPECT_FALSE(withheld_no_end(middle_out(0, 0, 0), paper));
}

// A pose is handed out only where the sensor resolves the tube: its relief (0.223 R, RMS) over the
// pixels confirming it, against the frame's measured noise, at least pick_min_relief_sigmas (a
// bent pipe pick_min_relief_sigmas_bent). 38 pixels of a 20 mm tube: 6.9 sigmas at 2 mm of noise,
// 2.7 at 5 mm.
TEST(Decide, APoseIsHandedOutOnlyWhereTheSensorResolvesTheTube) {
  Verification small;
  small.model_px = small.inner_px = 40;
  small.agree_px = 38;
  EXPECT_NEAR(tube_relief_sigmas(small, kD, 5), std::sqrt(38.0) * 0.223 * 10 / 5, 1e-3);
  LocateConfig cfg;
  cfg.frame_noise_mm = 2;
  Decision d = decide(judged(small), cfg);
  EXPECT_EQ(d.outcome, CandidateOutcome::accepted);
  EXPECT_TRUE(d.pickable);
  EXPECT_FALSE(d.unresolved);
  cfg.frame_noise_mm = 5;
  d = decide(judged(small), cfg);
  EXPECT_EQ(d.outcome, CandidateOutcome::accepted);  // still reported, with its score
  EXPECT_FLOAT_EQ(d.score, 0.95f);
  EXPECT_FALSE(d.pickable);
  EXPECT_TRUE(d.unresolved);
  // A pose not pickable for another reason is not "unresolved": the noise is not what holds it.
  Verification covered = small;
  covered.agree_px = 30, covered.occluded_px = 10;
  d = decide(judged(covered), cfg);
  EXPECT_FALSE(d.pickable);
  EXPECT_FALSE(d.unresolved);
  // 3.4 sigmas (4 mm of noise): too little for a bend (pick_min_relief_sigmas_bent), whose turn
  // about its length the relief places too; thin short bends picked over 10 mm off while clearing
  // showed 3.3-3.7. A straight tube's turn about its axis is the same pick: it is handed out.
  cfg.frame_noise_mm = 4;
  EXPECT_NEAR(tube_relief_sigmas(small, kD, 4), 3.44f, 0.01f);
  EXPECT_TRUE(decide(judged(small), cfg).unresolved);
  Evidence straight = judged(small);
  straight.model_slides = straight.model_straight = true;
  EXPECT_TRUE(decide(straight, cfg).pickable);
  cfg.frame_noise_mm = 0;  // no noise known: nothing to hold the pose back for
  EXPECT_TRUE(decide(judged(small), cfg).pickable);
  cfg.frame_noise_mm = 5;
  cfg.pick_min_relief_sigmas = 0;  // off
  d = decide(judged(small), cfg);
  EXPECT_TRUE(d.pickable);
  EXPECT_FALSE(d.unresolved);
}

// An accepted pose that is not handed out says why: a bit for each check it fails, none where it
// is pickable (the overlay's label, `locate`'s `withheld`, the timing log's counts).
TEST(Decide, APoseNotHandedOutSaysWhy) {
  LocateConfig cfg;
  const auto why = [&](const Evidence& e) {
    const Decision d = decide(e, cfg);
    EXPECT_EQ(d.outcome, CandidateOutcome::accepted);
    EXPECT_EQ(d.withheld == 0, d.pickable) << "withheld " << d.withheld;
    return d.withheld;
  };
  EXPECT_EQ(why(judged(seen(950, 0, 0))), 0u);
  EXPECT_EQ(why(judged_with_rival(seen(950, 0, 0), seen(950, 0, 0))), unsigned(kWithheldAmbiguous));
  EXPECT_EQ(why(judged(seen(800, 0, 200))), unsigned(kWithheldCovered));  // 20 % under others
  EXPECT_EQ(why(judged(outside_view(seen(950, 0, 0), 0.6f))), unsigned(kWithheldPartSeen));
  EXPECT_EQ(why(ends_read(judged(seen(950, 0, 0)), 0, 2, 0, 0)), unsigned(kWithheldGoesOn | kWithheldNoEnd));
  EXPECT_EQ(why(ends_read(judged(seen(950, 0, 0)), 0, 0, 0, 0)), unsigned(kWithheldNoEnd));
  EXPECT_EQ(why(searched_again(judged(with_sides(seen(800, 0, 0), 100, 10)))),
            unsigned(kWithheldSecondSearch));
  Verification small = seen_on(38, 40);
  cfg.frame_noise_mm = 5;  // 2.7 sigmas: the sensor does not resolve the tube
  EXPECT_EQ(why(judged(small)), unsigned(kWithheldUnresolved));
  small.occluded_px = 8;  // and it lies under another pipe: both said
  EXPECT_EQ(why(judged(small)), unsigned(kWithheldCovered | kWithheldUnresolved));
  for (int k = 0; k < kWithheldKinds; ++k) EXPECT_STRNE(withheld_name(k), "?");
  EXPECT_STREQ(withheld_name(0), "ambiguous");
  EXPECT_STREQ(withheld_label(kWithheldKinds - 1), "TOOK NOTHING");
  EXPECT_EQ(withheld_index(kWithheldUnresolved), 6);
  EXPECT_EQ(withheld_index(kWithheldTookNothing), kWithheldKinds - 1);   // the service's, named last
  EXPECT_EQ(withheld_index(kWithheldCovered | kWithheldUnresolved), 1);  // the first check failed
  EXPECT_EQ(withheld_index(0), kWithheldKinds);
}

// The pixels telling a pose from its rival are read at 3 sigmas of the frame's noise where that
// is finer than the verify tolerance; with no noise measured, at the tolerance.
TEST(Decide, TellingPixelsAreReadAtTheNoiseWhereItIsFinerThanTheTolerance) {
  LocateConfig cfg;
  cfg.verify_tolerance_mm = 7;
  cfg.frame_noise_mm = 1.5;  // a Kinect-class sensor at 0.7 m
  EXPECT_FLOAT_EQ(telling_tolerance_mm(cfg), 4.5f);
  cfg.frame_noise_mm = 3.5;  // an active-stereo sensor at 1.15 m: the tolerance is finer
  EXPECT_FLOAT_EQ(telling_tolerance_mm(cfg), 7.0f);
  cfg.frame_noise_mm = 0;
  EXPECT_FLOAT_EQ(telling_tolerance_mm(cfg), 7.0f);
}

// A pose turned about the pipe's length takes the found one's place only where the image shows
// its ends no worse: frame 22 of a 23-planar bin (bin seed 1022) had the found pose pin an end
// (quality 0.840) and its half-turn, laid over the pipe running out of the view, pin none (0.909):
// the turn was handed out, 330 mm off.
TEST(Decide, ATurnAboutItsLengthReplacesThePoseOnlyWhereItsEndsShowNoWorse) {
  const auto ends = [](int pinned, int continued) {
    Verification v = seen(900, 0, 0);
    v.ends_pinned = pinned, v.ends_continued = continued;
    return v;
  };
  EXPECT_FALSE(turn_may_replace(ends(0, 0), ends(1, 0)));  // the frame above
  EXPECT_TRUE(turn_may_replace(ends(1, 0), ends(1, 0)));
  EXPECT_TRUE(turn_may_replace(ends(2, 0), ends(1, 0)));
  EXPECT_TRUE(turn_may_replace(ends(0, 0), ends(0, 0)));  // neither shows an end: the image decides
  EXPECT_FALSE(turn_may_replace(ends(1, 1), ends(0, 0)));  // the tube goes on beyond the turn's end
}

// Another part of the pipe in view is judged against a pose by its ends too: an end the pose pins
// speaks for it, unless the other part's end lies there as well (shared), read by the same probes.
// Seed 22's 11-S-asym of the zoo was handed out 491 mm off, its other bend on the bend in view: its
// end in view pinned, the pipe's end there too, unpinned. A pinned pose's other part at both its
// ends is that pose barely moved: a straight tube half out of the view lost 11 of 90 picks to such
// "other parts" 2.7-10 mm away (seed 20's 01-straight).
TEST(Decide, AnotherPartsEndsAreJudgedSharedEndsAside) {
  const auto ends = [](int pinned, int continued) {
    Verification v = seen(900, 0, 0);
    v.ends_pinned = pinned, v.ends_continued = continued;
    return v;
  };
  EXPECT_FALSE(other_part_ends_no_worse(ends(0, 0), ends(1, 0), 0));  // the pin speaks for the pose
  EXPECT_TRUE(other_part_ends_no_worse(ends(0, 0), ends(1, 0), 1));   // the S above: a shared end
  EXPECT_TRUE(other_part_ends_no_worse(ends(1, 0), ends(1, 0), 0));
  EXPECT_FALSE(other_part_ends_no_worse(ends(0, 0), ends(2, 0), 1));  // its other end pinned too
  EXPECT_FALSE(other_part_ends_no_worse(ends(1, 0), ends(1, 0), 2));  // the straight tube above
  EXPECT_TRUE(other_part_ends_no_worse(ends(0, 0), ends(0, 0), 2));   // no pin: as before
  EXPECT_FALSE(other_part_ends_no_worse(ends(0, 1), ends(0, 0), 2));  // the tube goes on beyond it
}

// Of a pipe that slides along itself, a pose its ends place goes before one they show slid where
// the image confirms both about as well: the zoo's 31 mm coil (stereo, bin seed 1017, frame 1) had
// its top coil found 211 mm round its helix, the tube going on beyond one end and no end pinned
// (agreement 0.94), over its right pose with an end pinned (0.90, the rest unread). Nowhere else:
// a neighbour touching a right pose's end also reads as the tube going on.
TEST(Decide, OfAPipeThatSlidesAPoseItsEndsPlaceGoesBeforeOneTheyShowSlid) {
  const LocateConfig cfg;
  const auto ends = [](int agree_px, int pinned, int continued) {
    Verification v = seen(agree_px, 0, 0);
    v.ends_pinned = pinned, v.ends_continued = continued;
    return v;
  };
  const Verification right = ends(900, 1, 0), slid = ends(940, 0, 1);
  EXPECT_TRUE(better_reading(right, slid, true, cfg));  // the coil above
  EXPECT_FALSE(better_reading(slid, right, true, cfg));
  EXPECT_FALSE(better_reading(right, slid, false, cfg));  // a pipe that does not slide: the image decides
  EXPECT_FALSE(better_reading(ends(880, 1, 0), slid, true, cfg));  // not about as well confirmed
  EXPECT_TRUE(better_reading(slid, ends(880, 1, 0), true, cfg));
  EXPECT_FALSE(better_reading(ends(900, 1, 1), slid, true, cfg));             // its own end goes on too
  EXPECT_FALSE(better_reading(ends(900, 0, 0), slid, true, cfg));             // no end pinned
  EXPECT_FALSE(better_reading(right, ends(940, 1, 1), true, cfg));            // the other pinned at one end
  EXPECT_FALSE(better_reading(ends(650, 1, 0), ends(690, 0, 1), true, cfg));  // neither confirmed
}

}  // namespace
}  // namespace pipeloc
