// What the status page says of the service that does not change while it runs, and one snapshot
// of what does: both given to the page's renderers, which only format.
#pragma once

#include <string>
#include <vector>

#include "core/clock.hpp"
#include "service/status_board.hpp"

namespace pipeloc {

struct StatusInfo {
  std::string model, source, plc;   // the start-up log's one-line descriptions
  std::string config_path;          // "" = the embedded default
  std::vector<std::string> config;  // every value in effect ("section.key = value  # unit")
  double budget_ms = 0;
  int refresh_s = 3;
  double start_unix_ms = 0;
};

// A snapshot as the page's thread holds it, with when it was taken.
struct StatusView {
  StatusSnapshot s;
  std::vector<CycleSample> history;  // s's ring in time order
  double now_unix_ms = 0;
  Clock::time_point now{};
};

}  // namespace pipeloc
