// /api/status: what the page shows, as JSON (times in ms, Unix ms for clock times).
#pragma once

#include <string>

#include "status/status_info.hpp"

namespace pipeloc {

std::string render_status_json(const StatusView& view, const StatusInfo& info);

}  // namespace pipeloc
