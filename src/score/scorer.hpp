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

  double top_recall(int bound_mm) const;
  double best_correct(int bound_mm) const;
  double precision_10() const;
  double time_median_s() const;
  double time_p95_s() const;
  void add(const ScoreCounts& other);
};

struct ScoreReport {
  std::map<int, ScoreCounts> per_object;  // obj_id -> counts
  std::map<int, std::string> object_names;
  ScoreCounts overall;
  int malformed_rows = 0;
  std::vector<std::string> malformed_examples;
  int rows_outside_targets = 0;
};

struct ScoreParams {
  double top_occlusion_max = 0.15;  // best-correct: the pick must be covered at most this much
};

// Reads ground truth from the dataset; throws IoError if the dataset itself is unreadable.
ScoreReport score_results(const std::string& dataset, const ResultsFile& results, const ScoreParams& = {});

std::string format_report(const ScoreReport& report);
Json report_to_json(const ScoreReport& report);

}  // namespace pipeloc
