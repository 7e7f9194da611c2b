// /metrics: the Prometheus text exposition format 0.0.4 (# HELP, # TYPE, samples), names
// pipeloc_*, seconds as the base unit.
#pragma once

#include <string>

#include "status/status_info.hpp"

namespace pipeloc {

std::string render_metrics(const StatusView& view, const StatusInfo& info);

}  // namespace pipeloc
