#include "service/frame_source.hpp"

#include <cmath>

#include "service/openni2_source.hpp"
#include "service/replay_source.hpp"
#include "service/sim_source.hpp"

namespace pipeloc {

const char* grab_status_name(GrabStatus s) {
  switch (s) {
    case GrabStatus::ok:
      return "ok";
    case GrabStatus::sensor_unavailable:
      return "sensor_unavailable";
    case GrabStatus::frame_invalid:
      return "frame_invalid";
  }
  return "?";
}

std::unique_ptr<FrameSource> open_frame_source(const AppConfig& cfg, const PipeModel& model) {
  if (cfg.source.kind == "sim") return std::make_unique<SimSource>(model, cfg.source.sim);
  if (cfg.source.kind == "replay") return std::make_unique<ReplaySource>(cfg.source.replay);
  if (cfg.source.kind == "openni2") return std::make_unique<OpenNi2Source>(cfg.source.openni2);
  throw SourceError("source.kind '" + cfg.source.kind + "': expected sim, replay or openni2");
}

GrabStatus check_frame(const Image<float>& depth, const Intrinsics& expected, double min_valid_share,
                       const char** why) {
  const char* unused;
  if (!why) why = &unused;
  *why = "";
  if (depth.width != expected.width || depth.height != expected.height ||
      depth.pixels.size() != std::size_t(expected.width) * std::size_t(expected.height))
    return *why = "size differs from the intrinsics", GrabStatus::frame_invalid;
  std::size_t valid = 0;
  for (const float z : depth.pixels) {
    if (!std::isfinite(z)) return *why = "a depth is NaN or infinite", GrabStatus::frame_invalid;
    if (z < 0) return *why = "a depth is negative", GrabStatus::frame_invalid;
    valid += z > 0;
  }
  if (double(valid) >= min_valid_share * double(depth.pixels.size())) return GrabStatus::ok;
  *why = "too few pixels with depth";
  return GrabStatus::frame_invalid;
}

std::size_t valid_depth_pixels(const Image<float>& depth) {
  std::size_t valid = 0;
  for (const float z : depth.pixels) valid += std::isfinite(z) && z > 0;
  return valid;
}

}  // namespace pipeloc
