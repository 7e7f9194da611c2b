// The status page: plain HTML with inline SVG, reloading itself every status.refresh_s, readable
// without the README: the latest overlay, the last LOCATE's poses, the cycle-time plots, counts
// since start, the last results, the PLC clients and the config in effect.
#pragma once

#include <string>

#include "status/status_info.hpp"

namespace pipeloc {

std::string render_status_page(const StatusView& view, const StatusInfo& info);
// Text safe inside HTML elements and attribute values.
std::string html_escape(const std::string& text);
// "2026-11-24 05:01:02" (UTC) from Unix milliseconds.
std::string utc_time_text(double unix_ms);
const char* command_name(std::uint16_t command);

}  // namespace pipeloc
