// The status page's two plots as inline SVG: the histogram of recent LOCATE cycle times (budget,
// p50 and p95 marked) and the cycle time over time, each dot coloured by the outcome.
#pragma once

#include <string>
#include <vector>

#include "service/status_board.hpp"

namespace pipeloc {

std::string svg_cycle_histogram(const std::vector<CycleSample>& samples, double budget_ms);
std::string svg_cycle_over_time(const std::vector<CycleSample>& samples, double budget_ms,
                                double now_unix_ms);

}  // namespace pipeloc
