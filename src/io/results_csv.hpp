// BOP results CSV: scene_id,im_id,obj_id,score,R,t,time (R 9 and t 3 space-separated values).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "core/pose.hpp"

namespace pipeloc {

struct ResultRow {
  int scene_id = 0, im_id = 0, obj_id = 0;
  double score = 0;
  Pose model_to_cam = Pose::Identity();
  double time_s = -1;
};

struct ResultsFile {
  std::vector<ResultRow> rows;
  int malformed = 0;                      // rows that could not be read
  std::vector<std::string> first_errors;  // "line N: why", a few of them
};

ResultsFile read_results_csv(const std::string& path);  // throws IoError only if unreadable
void write_results_header(std::ostream& out);
void write_result_row(std::ostream& out, const ResultRow& row);

}  // namespace pipeloc
