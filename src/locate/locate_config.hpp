// Every threshold of the localizer, with its unit and a default. Sizes in mm that depend on the
// pipe are given as shares of the tube diameter D or the longest extent L, which come from the
// model; noise-dependent values follow the sensor model of DESIGN.md.
#pragma once

namespace pipeloc {

// The bin interior in the bin frame (pipeloc calibrate-bin prints it): depth points outside it
// never enter the Z-buffer, so bin walls and rims give no candidates. Off when unset (min >= max).
struct RegionOfInterest {
  double min_x_mm = 0, min_y_mm = 0, max_x_mm = 0, max_y_mm = 0;
  bool on() const { return min_x_mm < max_x_mm && min_y_mm < max_y_mm; }
};

struct LocateConfig {
  RegionOfInterest roi;  // [locate] roi_min_mm / roi_max_mm

  // Beyond the paper: a reading nearer or farther than every reading within 2 pixels by more than
  // continuity_step_max_mm is a speckle (a sensor's stray reading), left out (locate/speckles.hpp).
  bool remove_speckles = true;

  // II-A: Z-buffer and normals.
  double zbuffer_pixel_mm = 1.0;        // the paper's 1 mm cells
  double zbuffer_max_side_mm = 1600;    // the Z-buffer covers at most this square of the bin
  // The frame's depth noise is measured (locate/thresholds.cpp) and R_th and the verification's
  // tolerance are raised to what it needs when it needs more (1.8 and 3 sigma): a thin tube far
  // from a noisy sensor. Off: the values below alone.
  bool raise_to_noise = true;
  // A length in mm left at 0 is derived (locate/thresholds.cpp): hole fill from D, the normal
  // window from D and the frame's noise, the noise-dependent three from the depth noise measured in
  // each frame. The window is derived by default; the other four keep fixed defaults: derived, they
  // cost the zoo (docs/experiments.md, "Thresholds", "Normal window").
  double hole_fill_mm = 8.0;      // glint holes up to this wide are filled (0: 0.44 D; under 2 cells: none)
  double normal_window_mm = 0;    // plane-fit neighbourhood (0: derived per frame: 0.35 D, the part of
                                  // the tube that is locally plane, but at least sqrt(8 sigma c), c a
                                  // sample's spacing, and 2.5 pixel footprints)
  double normal_min_valid_share = 0.4;  // of the window's cells; fewer and the cell has no normal

  // II-B, Algorithm 1: candidate regions.
  double upward_normal_max_deg =
      45;  // core cells: N . Nv > cos(this) (N_th1); pipes resting on others tilt this far
  double continuity_max_deg =
      35;  // growth: N_i . N_j > cos(this); 3 sigma of two 7 mm plane fits plus the turn per cell
  double continuity_step_max_mm = 8;  // growth: no jump between neighbours (3.4 sigma of a Kinect-class
                                      // sensor's noise at 1.1 m; 0: 3.4 sigma of the frame's measured noise)
  double core_min_area_of_d2 = 0.75;    // A_th = this * D^2
  double core_max_extent_of_l = 1.15;   // a core longer than the pipe is not one pipe (bin rims, floor)
  double core_valley_turn = 0.5;        // ... unless it splits where the normals D/4 either side turn
                                        // towards each other by more (unit-normal components; 0: off)
  double core_split_max_area_of_ld = 8;  // ... and is not larger than this * L * D (else it is floor)
  double core_whole_max_extent_of_l = 2.3;  // a core too long that no valley splits is kept whole up to
                                            // this * L (two pipes end to end; 0: dropped, the paper's)
  double region_min_extent_of_l = 0.7;  // a of the paper
  double short_region_min_extent_of_l = 0.5;  // shorter regions down to this * L are tried after the
                                              // others (region_min_extent_of_l: off, the paper's cut)
  double region_max_drop_of_d = 0.8;    // grown cells lie at most this far below their core
  double region_max_reach_of_d = 1.0;   // ... and at most this far from it (steps of growth)
  double region_join_gap_of_d = 3;  // a region too short is joined to the piece of top strip that
                                    // continues it across a gap up to this * D (a pipe lying across,
                                    // a dropout): same direction, same height (0: off)
  double hole_bridge_of_d = 0;  // growth crosses holes in the top strip up to this * D long (0: off;
                                // 1 bridges dropouts but costs the dev set 0.012 recall@5)
  double region_max_claimed_share = 0.75;  // a region with more of its cells in earlier candidates'
                                           // regions is another piece of a pipe already tried
  bool retry_claimed_cores = true;  // a core lying in an earlier candidate's region is grown again
                                    // after all the others, while there is room (the region over it
                                    // may be a touching neighbour's; false: the paper's one region)
  bool leftover_regions = true;     // what an accepted pose leaves of its region unexplained, when
                                    // long enough, is tried as a candidate of its own (false: the
                                    // paper's one pipe per region)
  // Of the cells grown straight from a core, at least this share tilt away from it: a majority
  // (a floor patch between pipes tilts towards it). Not more: the noisy normals of a thin tube
  // tilt away by a small majority only (the zoo's 8.4 mm elbow: 0.5-0.58 on three top pipes).
  double convexity_min_share = 0.5;

  // III: principal direction by cross-section widths.
  double section_width_min_of_d = 0.85;  // the paper's 0.9R..1.0R, widened by one cell each side
  double section_width_max_of_d = 1.05;
  double scan_step_deg = 5;

  // IV: Z-ridge ICP from 2 x initial_rotations starts.
  double ridge_cell_mm = 2.0;
  int initial_rotations = 6;         // turns about the axis: 0/60/.../300 degrees (IV-B's six initial states)
  double initial_yaw_step_deg = 30;  // each start also turned about the vertical in these steps (180: not)
  double start_slide_step_of_d =
      1.0;  // initial states slid in steps of this * D across the axis, twice along
  bool slide_starts = true;  // beyond the paper: each start slid to where its ridge covers the observed one
                             // (along the axis up to L/4 either way ...
  double edge_slide_along_of_l = 0.5;  // ... up to this * L where the observed ridge reaches the view's
                                       // edge: the pipe may lie anywhere along it beyond; 0: L/4 there too)
  int icp_max_iterations = 24;
  int icp_probed_states = 48;      // of the slid starts, the best this many (by ridge cover) are probed
                                   // (72 = all of 2 x 6 turns x 6 yaws; fewer trade recall for time),
  int icp_probe_iterations = 3;    // each gets this many iterations ...
  double icp_probe_cell_mm = 4.0;  // ... on ridges of this cell size (coarse: a quarter of the work)
  int icp_continued_states = 8;    // ... and the best this many run to convergence,
  int icp_continued_states_sliding = 4;  // ... this many for a pipe that slides along itself (its
                                         // further states are the pipe slid, which the image does
                                         // not tell apart)
  int icp_fine_iterations = 8;     // the last this many on ridge_cell_mm, the others on the probe cells
  double icp_converged_mm = 0.05;
  double residual_max_of_d = 0.35;  // R_th = this * D (mean ridge distance; verification follows)
  double residual_rescue_of_rth = 1.5;  // where no fit is under R_th, fits under this * R_th are
                                        // judged by the image instead (1: off, the paper's cut)
  // Beyond the paper: a region whose ridge fits end in a pose the image does not confirm is
  // searched again, matching the whole top surface of the region instead of its Z-ridge, on
  // cells of this * D (at least ridge_cell_mm; probes on twice that); the service runs these
  // searches after the PLC has its result. 0: off (the zoo's top pipes found 852 of 912 -> 834;
  // the time to the pick the same; docs/experiments.md).
  double retry_surface_cell_of_d = 0.25;
  // ... their poses are reported, and handed out only where the first searches hand out none:
  // the cycle then waits for them, and a pose of theirs is pickable only where the image confirms
  // verify_well_seen_agreement of what is in view and under nothing in front, and its sides drop
  // away (judged on enough side pixels). Off: never handed out.
  bool second_search_may_pick = true;
  double residual_noise_floor_mm = 0;  // R_th is at least this (set per frame by raise_to_noise, not a key)
  double frame_sigma_mm = 0;           // the frame's measured depth noise (set per frame, not a key)
  double frame_noise_mm = 0;           // ... not capped as the thresholds' is (set per frame, not a key)

  // Beyond the paper: surface refinement, verification, ambiguity.
  int refine_iterations = 12;
  int refine_max_points = 1500;            // observed points used by the refinement
  bool refine_on_explained = true;  // then again on every pixel the refined pose explains (the
                                    // whole pipe seen, not only its region's top strip), if better
  bool twins_refined_on_region = true;  // a near twin of a pipe that does not slide is refined on its
                                        // region too, not only on every pixel the best explains
  bool polish_best = true;          // the best reading refined once more on every pixel it explains, kept
                                    // where the image confirms it and shows its ends as well and it
                                    // stays the same reading (not for a pipe that slides along itself)
  bool refine_facing_only = true;  // a point pairs only with model surface facing the camera (a
                                   // reading beside a thin tube is not its hidden underside; not for
                                   // a pipe that slides along itself: surface_refine.hpp)
  bool refine_ray_pairs = false;   // a point pairs with the tube where the camera's ray through it
                                   // meets it, not with the nearest sample (whose pairs read a thin
                                   // tube's noise as lying nearer the camera), in the refinement's
                                   // last iterations; off: six bins of every shape of the zoo take
                                   // fewer pipes with it, at 1.15x the cycle (docs/experiments.md)
  double refine_inlier_mm = 4;     // point-to-plane pairs farther than this are not the pipe
                                   // (0: 1.7 sigma of the frame's measured noise, at least 0.2 D)
  double verify_tolerance_mm = 7;  // depth agreement, 3 sigma of a Kinect-class sensor's noise at 1.1 m
                                   // (0: 3 sigma of the frame's measured noise, at least 2.5 mm)
  double verify_min_agreement = 0.7;       // share of the model's visible pixels the sensor confirms
  double verify_min_read_share = 0.5;      // ... of those it read, for a pose both its ends are seen
                                           // ending, at least this share of them counted (1: unread
                                           // ones count against it)
  double verify_max_free_space = 0.05;     // share of model pixels where the sensor saw through it ...
  double free_space_band_of_d = 0.125;     // ... not counting a band this * D wide inside the rim
                                           // (in pixels at the pose's distance; 0: the rim only)
  double verify_max_occluded = 0.15;       // share of model pixels covered by something in front
  double verify_max_outside_view = 0.3;    // share of the model's vertices outside the image (and
                                           // agreement * (1 - this share) >= verify_min_agreement)
  double verify_max_outside_view_well_seen = 0.5;  // ... or up to this share where what is in view
  double verify_well_seen_agreement = 0.9;         // ... agrees this well (or what of it lies
                                                   // under nothing in front, a sliding pipe then
                                                   // showing an end seen ending; and, where the
                                                   // ends are read, one end is pinned); an
                                                   // ambiguous pose further out of view is no
                                                   // estimate
  double verify_max_outside_view_ends_seen = 0.75;  // ... or up to this share where, of a pipe
                                                    // that does not slide along itself, what is
                                                    // in view agrees as well and both its ends
                                                    // are seen ending outright, the tube going on
                                                    // beyond neither (0: off)
  double side_drop_of_d = 0.25;            // a pipe's surroundings lie at least this * D beyond its silhouette ...
  double verify_max_side_level = 0.3;      // ... but for at most this share (more: a smooth blob, not a pipe)
  // Beyond the paper: a pose is handed out only where the sensor resolves the tube: its relief (a
  // tube's top departs from the plane through it by 0.223 R, RMS over its width), summed over the
  // pixels confirming the pose, is at least this many sigmas of the frame's measured noise. A thin
  // short elbow at 1 m under an active-stereo sensor is not (1.4-1.9 sigmas: 13 picks, 1 right).
  // 0: off.
  double pick_min_relief_sigmas = 3;
  // ... and at least this many for a pipe that is not a straight tube: its turn about its own
  // length is read from that relief too (a straight tube's is the same pick). Of the nineteen wrong
  // picks of twelve bins of every zoo shape, six were thin short bends at 3.3-3.7 sigmas; thin
  // straight tubes were picked right there (docs/experiments.md).
  double pick_min_relief_sigmas_bent = 4;
  int verify_hypotheses = 3;               // distinct ridge fits refined and checked per region
  double ambiguity_pose_mm = 10;           // two fits further apart than this (MSSD) ...
  double ambiguity_quality_margin = 0.05;  // ... both confirmed within this margin (or within two
                                           // standard errors of the best's agreement, the larger): ambiguous
  bool tell_rivals_apart = true;           // ... unless, where the two differ, the image speaks for the best
                                           // (kMinTellingPx pixels at telling_tolerance_mm) and at most a
                                           // quarter as much for the rival
                                           // (not for a pipe that slides along itself: its ends place it)
  bool rivals_judged_where_seen = true;    // where no end of the best is pinned, a rival within the margin
                                           // over the pixels read where nothing lies in front is as good
                                           // (its part under a pipe says nothing)
  bool judge_rolls = true;        // the found pose turned about the pipe's own length by quarter turns
                                  // (eighths where a quarter turn lands it mostly on itself); and
                                  // so a rival as good, which may be handed out in its place
  double roll_ambiguity_mm = 5;   // ... a turn the image confirms as well that moves the pick further
                                  // than this (the pick-correct tolerance): ambiguous ...
  bool tell_rolls_apart = true;   // ... unless, where the two differ, the image speaks for the found
                                  // pose and hardly for the turn (as tell_rivals_apart)
  bool judge_other_parts = true;  // a pose reaching out of the view, no end going on, put with
                                  // another part of the pipe where its part in view is seen (an
                                  // S's other bend): as good on the pixels read, its ends no worse
                                  // (an end both lie at counts for neither), ambiguous; the best,
                                  // and a rival as good that may be handed out instead
  // A pose further from the camera than where one pixel covers its near twin's spread everywhere
  // (twin_resolved_within_mm): ambiguous, whatever its pixels say.
  bool twin_beyond_resolution_ambiguous = true;
  bool rivals_across_regions = true;  // two regions' estimates that read one pipe two ways, the
                                      // image confirming both about as well: both ambiguous (both
                                      // in view: the one whose ends show worse dropped); the image
                                      // confirming one clearly worse: that one ambiguous
  bool judge_slides = true;  // the found pose slid along the pipe itself (an arc about its centre,
                             // a coil along its helix, a straight run along its axis) is a rival too
  bool pin_slides_by_ends = true;  // a pipe that slides along itself is pickable only where the
                                   // image shows one of its ends, and no end goes on beyond; every
                                   // pipe's ends are read (off: none)
  bool ends_read_further = true;   // ... and where nothing is read just beyond a sliding pipe's
                                   // end, the image is read 2 D beyond along its bend
  bool ends_read_slanted = true;   // ... and the tip of an end the tube reaches at a slant to the
                                   // image is read where such a tube shows its surface (judge_ends)
  bool ends_probed_past_itself = true;  // ... and beyond a tip of a pipe that does not slide, the
                                        // image is read past where it shows the pose's own tube
                                        // (judge_ends)
  bool slides_placed_first = true;  // ... and of two of its hypotheses the image confirms about as
                                    // well, one its ends place goes before one they show slid
                                    // (with judge_slides: its slid rivals check the pose put first)
  bool place_slides_finely = true;  // ... and a pose of it its ends pin is moved along itself by
                                    // up to D in D/12 steps to where the image confirms the most
                                    // and sees through the least of it, if its ends show no worse
  bool follow_slides_to_ends = true;  // ... and a pose of it the tube goes on beyond, no end pinned,
                                      // is moved along itself by D, 2 D, ... to where the image
                                      // shows one of its ends ending outright
  bool pin_part_in_view_by_ends = true;  // a pose reaching out of the view whose part in view
                                         // slides along the pipe (an arc's or a coil's loop) is
                                         // pickable only where an end in view is seen ending
                                         // outright and no end goes on (judge_part_in_view)
  bool end_unread_as_out_of_view = true;  // ... and a pose of a pipe that does not slide, reaching
                                          // out of the view at one end, whose end in view the image
                                          // neither pins nor shows going on, is placed by the bends
                                          // in view as where both ends lie out of it
  bool end_shown_where_both_in_view = true;  // a pose of a pipe that does not slide with both ends
                                             // in the view is placed only where the image shows one
                                             // of them, though some of its middle lies out of it

  // The paper's comparison: ICP on points sampled from the whole visible surface instead of the
  // Z-ridge (eval-bop --match surface).
  bool match_surface = false;

  // Choice of the pick and fixed sizes.
  int max_candidates = 32;
  // Of them at most this many shorter than a * L: each costs as much time as a long one.
  int max_short_candidates = 8;
  int max_results = 0;  // poses reported per image; 0: every pose found (at most max_candidates)
  int threads = 2;
  int result_cap() const { return max_results > 0 ? max_results : max_candidates; }
  // The relief a pose of the pipe needs to be handed out (0: none), and the key that sets it (for
  // the log): pick_min_relief_sigmas_bent for a pipe that is not a straight tube where it asks
  // more, else pick_min_relief_sigmas, which at 0 turns both off.
  struct ReliefBound {
    double sigmas;
    const char* key;
  };
  ReliefBound min_relief(bool straight_tube) const {
    if (!(pick_min_relief_sigmas > 0)) return {0, "pick_min_relief_sigmas"};
    if (!straight_tube && pick_min_relief_sigmas_bent > pick_min_relief_sigmas)
      return {pick_min_relief_sigmas_bent, "pick_min_relief_sigmas_bent"};
    return {pick_min_relief_sigmas, "pick_min_relief_sigmas"};
  }
};

// The paper's search (IV-B): its six turns in both directions at the measured centre, every one
// run to convergence, no turns about the vertical, no sliding, no slid rivals (nor poses put
// first by their ends), R_th a hard cut.
// The checks after the search (refinement, verification, ambiguity) stay. `--search paper` /
// [locate] search.
inline void use_paper_search(LocateConfig* c) {
  c->initial_rotations = 6;
  c->initial_yaw_step_deg = 180;
  c->slide_starts = false;
  c->icp_probed_states = 2 * c->initial_rotations;
  c->icp_continued_states = c->icp_continued_states_sliding = 2 * c->initial_rotations;
  c->judge_slides = false;
  c->slides_placed_first = false;
  c->place_slides_finely = false;
  c->follow_slides_to_ends = false;
  c->pin_part_in_view_by_ends = false;
  c->end_unread_as_out_of_view = false;
  c->end_shown_where_both_in_view = false;
  c->verify_max_outside_view_ends_seen = 0;
  c->ends_read_further = false;
  c->ends_read_slanted = false;
  c->ends_probed_past_itself = false;
  c->judge_rolls = false;
  c->judge_other_parts = false;
  c->rivals_judged_where_seen = false;
  c->residual_rescue_of_rth = 1;
  c->short_region_min_extent_of_l = c->region_min_extent_of_l;
  c->leftover_regions = false;
  c->retry_surface_cell_of_d = 0;
  c->second_search_may_pick = false;
}

}  // namespace pipeloc
