// The one clock of the cycle and its conversions to and from milliseconds.
#pragma once

#include <chrono>
#include <ctime>
#include <string>

namespace pipeloc {

using Clock = std::chrono::steady_clock;

inline double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}
inline double ms_since(Clock::time_point t0) { return ms_between(t0, Clock::now()); }
inline Clock::duration ms_duration(double ms) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(ms));
}
// Wall-clock time (for logs a person reads), ms since the Unix epoch.
inline double unix_ms_now() {
  return std::chrono::duration<double, std::milli>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
// "2026-11-23 18:45:44" (UTC) from Unix milliseconds; another strftime format on request.
inline std::string utc_text(double unix_ms, const char* format = "%Y-%m-%d %H:%M:%S") {
  const std::time_t t = std::time_t(unix_ms / 1000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char s[64];
  std::strftime(s, sizeof s, format, &tm);
  return s;
}

}  // namespace pipeloc
