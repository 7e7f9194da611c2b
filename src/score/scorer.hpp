// The scorer of DESIGN.md: greedy matching by descending score under MSSD, top recall,
// best-correct, precision and time, per object and overall.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "io/bop.hpp"
#include "io/results_csv.hpp"

namespace pipeloc {

struct ScoreCounts {
  int images = 0;
  int top_pipes = 0;
  int top_matched_5 = 0, top_matched_10 = 0;
  int best_correct_5 = 0, best_correct_10 = 0;
  int estimates = 0, matched_10 = 0;
  std::vector<double> times_s;  // one per image that reported a time
  // What the PLC gets (score --picks): one handed-out pose per image at most.
  int pick_images = 0;     // images with a top pipe
  int picked_images = 0;   // ... in which a pose is handed out
  int picks = 0;           // handed-out poses, in any image
  int pick_correct_5 = 0;  // ... within 5 mm of a pipe covered at most top_occlusion_max
  int wrong_picks = 0;     // ... more than 10 mm from every such pipe

  double top_recall(int bound_mm) const;
  double best_correct(int bound_mm) const;
  double precision_10() const;
  double time_median_s() const;
  double time_p95_s() const;
  double pick_rate() const;         // picked_images / pick_images
  double pick_correct_5mm() const;  // pick_correct_5 / picks
  void add(const ScoreCounts& other);
};

// A top pipe no estimate matched within 5 mm, and how near the nearest came (score --misses).
struct TopMiss {
  int scene_id = 0, im_id = 0, obj_id = 0;
  int gt_index = 0;         // the pipe's place in scene_gt.json's list for the image
  double occ_by_pipes = 0;  // share of its silhouette covered by other pipes
  double visib_fract = 0;
  double nearest_mm = 0;  // MSSD of the nearest estimate (any rank; capped at kMissCapMm)
  int nearest_rank = -1;  // that estimate's rank by score (0: the highest), -1: no estimate
  double nearest_score = 0;
};
constexpr double kMissCapMm = 500;

struct ScoreReport {
  std::vector<TopMiss> misses;            // filled when score_results() is asked for them
  std::map<int, ScoreCounts> per_object;  // obj_id -> counts
  std::map<int, std::string> object_names;
  ScoreCounts overall;
  int malformed_rows = 0;
  std::vector<std::string> malformed_examples;
  int rows_outside_targets = 0;
  bool has_picks = false;  // the pick figures were computed (score --picks)
  int pick_rows_malformed = 0, pick_rows_outside_targets = 0;
  int pick_rows_extra = 0;  // second and later rows for one image (the PLC gets one pose)
};

struct ScoreParams {
  double top_occlusion_max = 0.15;  // best-correct and picks: the pipe covered at most this much
  double wrong_pick_mm = 10.0;      // a pick farther than this from every such pipe is wrong
};

// Reads ground truth from the dataset; throws IoError if the dataset itself is unreadable.
// `picks` (optional): the pose handed out per image (eval-bop --picks); no row = DONE_NONE.
// `list_misses`: also fill report.misses.
ScoreReport score_results(const std::string& dataset, const ResultsFile& results, const ScoreParams& = {},
                          const ResultsFile* picks = nullptr, bool list_misses = false);

// report.misses as CSV: a header, then one row per missed top pipe.
std::string format_misses(const ScoreReport& report);

std::string format_report(const ScoreReport& report);
Json report_to_json(const ScoreReport& report);

}  // namespace pipeloc
