// The timing log a maintainer reads on a deployed cell: one JSON line per cycle, and every
// `summary_every` cycles a summary line (p50/p95/p99/max of the cycle time). Files rotate by
// size: timing.jsonl -> timing.jsonl.1 -> ... -> .keep_files. Lines are formatted into a fixed
// buffer: writing a line allocates nothing (a rotation opens a new file).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "config/config_file.hpp"

namespace pipeloc {

struct CycleRecord;

class TimingLog {
 public:
  TimingLog(const LogConfig& cfg, int summary_every);  // throws std::runtime_error naming the folder
  ~TimingLog();
  TimingLog(const TimingLog&) = delete;
  TimingLog& operator=(const TimingLog&) = delete;

  void write(const CycleRecord& r);
  // Writes a line of the form {"event": ..., ...rest}; rest is a JSON fragment without braces.
  void event(const char* name, const char* rest_json);
  const std::string& path() const { return path_; }
  // Lines lost to a full disk or an unwritable folder; times the file was found gone and reopened.
  long write_errors() const { return write_errors_; }
  long reopened() const { return reopened_; }

  struct Summary {
    int cycles = 0;
    double p50 = 0, p95 = 0, p99 = 0, max = 0;
  };
  Summary summary() const;  // over the cycles since the last summary line

 private:
  void put(const char* line, int length);
  void rotate();
  bool reopen_if_gone();

  LogConfig cfg_;
  int summary_every_;
  std::string path_;
  std::FILE* file_ = nullptr;
  long bytes_ = 0;
  long write_errors_ = 0, reopened_ = 0;
  bool failing_ = false;
  std::vector<double> window_;  // cycle_ms since the last summary (capacity summary_every)
  mutable std::vector<double> sorted_;
  char line_[2048];
};

}  // namespace pipeloc
