// Thresholds in mm that follow the pipe and the sensor instead of one set: the keys of
// LocateConfig left at 0 ("derived") get their value from the tube diameter D (at start-up) and
// from the depth noise measured in each frame (DESIGN: "Thresholds follow from the model (D, L,
// bend radii) and from the sensor's noise and pixel footprint at the observed distance").
#pragma once

#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "locate/locate_config.hpp"

namespace pipeloc {

// What the frame tells of its sensor: the axial noise (1 sigma, quantisation included) and the
// median depth of its valid pixels.
struct DepthNoise {
  float sigma_mm = 0;
  float depth_mm = 0;
  int samples = 0;  // second differences measured
};

// A frame with fewer valid neighbour triples says little of its noise: a fallback stands in.
constexpr int kMinNoiseSamples = 500;

// Working memory of measure_depth_noise, sized once.
struct NoiseHistograms {
  std::vector<int> second_difference;  // |z(i-1) - 2 z(i) + z(i+1)| in kSecondDifferenceBinMm bins
  std::vector<int> depth;              // depth in kDepthBinMm bins
  NoiseHistograms();
};

// The noise from second differences of horizontally neighbouring pixels (a plane has none; of
// white noise sigma their deviation is sqrt(6) sigma), by the mean of their smallest 80 %, which
// the depth edges between pipes do not reach. No allocation.
DepthNoise measure_depth_noise(const Image<float>& depth_mm, NoiseHistograms* histograms);

// The keys that follow D alone, for a config whose such keys are 0 (derived); others kept.
LocateConfig with_model_thresholds(const LocateConfig& user, float tube_d_mm);

// The keys that follow the frame's noise and pixel footprint, from `user` (0: derived) into `cfg`.
void set_frame_thresholds(const LocateConfig& user, float tube_d_mm, const DepthNoise& noise,
                          const Intrinsics& camera, LocateConfig* cfg);

// The config of the second search of a region (retry_surface_cell_of_d): the whole top surface
// matched on cells of that * D (at least ridge_cell_mm), probed on twice that; else as `cfg`.
LocateConfig surface_retry_config(const LocateConfig& cfg, float tube_d_mm);

// Whether any key of `user` follows the frame (its noise or pixel footprint): only then is the
// frame's noise measured.
bool derives_from_frame(const LocateConfig& user);

// The largest refine_inlier_mm set_frame_thresholds gives for this D (the model index is built
// for it at start-up).
float max_refine_inlier_mm(const LocateConfig& user, float tube_d_mm);

}  // namespace pipeloc
