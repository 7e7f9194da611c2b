#include "locate/thresholds.hpp"

#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

constexpr float kSecondDifferenceBinMm = 0.05f;
constexpr int kSecondDifferenceBins = 800;  // up to 40 mm
constexpr float kDepthBinMm = 10.0f;
constexpr int kDepthBins = 1000;  // up to 10 m
// Of white noise sigma, the second difference has the deviation sqrt(6) sigma; the mean of its
// smallest 80 % in size (the largest are depth edges) is 0.5586 of that: 1.368 sigma. A mean, not
// the median: a quantised sensor's differences take a few discrete values, and their median jumps.
constexpr float kKeptShare = 0.8f;
constexpr float kTrimmedMeanOfSigma = 1.368f;
// Where the frame says too little of its noise (kMinNoiseSamples), the sensor model of DESIGN.md
// at 1 m (Kinect class) stands in.
constexpr float kFallbackSigmaMm = 2.0f, kFallbackDepthMm = 1000.0f;

// Model-derived (shares of D), chosen so that the paper's 16-20 mm tubes keep the values they
// were developed with (7 mm window, 4 passes of hole filling):
// the plane-fit window stays on the part of the tube that is locally plane, about D/3;
constexpr double kNormalWindowOfD = 0.35;
// glint holes on a tube's top are at most about half its width.
constexpr double kHoleFillOfD = 0.44;
// Noise-derived (multiples of the measured sigma, floors in Z-buffer cells or mm). The multiples are
// anchored on the sensor model the localizer was developed with: its frames at 1 m measure
// 2.37 mm, and there these give the values tuned then (8, 7 and 4 mm); elsewhere they scale with
// the noise (an active-stereo sensor at 0.6 m measures a third of it):
// two neighbouring cells of one surface differ by at most 3.4 sigma (2.4 sigma of the difference);
constexpr double kContinuityStepOfSigma = 3.4, kContinuityStepMinCells = 1.5;
// R_th with raise_to_noise: a right ridge fit's mean distance, 1.2-1.6 sigma where the noise
// outweighs the fit's own error (stereo at 1.1 m);
constexpr double kResidualOfSigma = 1.8;
// the verification's depth tolerance: 3 sigma, and never under the refined pose's own error;
constexpr double kVerifyToleranceOfSigma = 3.0, kVerifyToleranceMinMm = 2.5;
// the refinement's inlier gate: 1.7 sigma, or a fifth of the tube (the ridge fit's own error);
constexpr double kRefineInlierOfSigma = 1.7, kRefineInlierOfD = 0.2;
constexpr double kMaxSigmaMm = 4.0;  // beyond this no threshold grows further
// the plane-fit window spans at least this many pixel footprints (fewer fit the noise),
constexpr double kNormalWindowMinFootprints = 2.5;
// and its side w at least sqrt(this * sigma * c), c the larger of a Z-buffer cell and a pixel's
// footprint: a plane fitted to (w / c)^2 samples of noise sigma has a slope error of
// sqrt(12) sigma c / w^2, so this bounds it (to 0.43 rad per cell; the region growth judges many).
// The paper's sensor (2.37 mm at 1 m, 1.75 mm footprints) gives 5.8 mm, its 7 mm window in whole
// cells; on the zoo 8 did best of 4, 6, 8, 10, 12 and 20 (docs/experiments.md, "Normal window").
constexpr double kNormalWindowOfNoise = 8.0;

// The mean of the smallest `share` of the values in the histogram (bin centres).
float trimmed_mean_of(const std::vector<int>& histogram, int total, float share, float bin) {
  const double keep = double(share) * total;
  double seen = 0, sum = 0;
  for (std::size_t b = 0; b < histogram.size() && seen < keep; ++b) {
    const double take = std::min(double(histogram[b]), keep - seen);
    seen += take;
    sum += take * (double(b) + 0.5) * bin;
  }
  return seen > 0 ? float(sum / seen) : 0.0f;
}

float median_of(const std::vector<int>& histogram, int total, float bin) {
  int seen = 0;
  for (std::size_t b = 0; b < histogram.size(); ++b) {
    seen += histogram[b];
    if (2 * seen >= total) return (float(b) + 0.5f) * bin;
  }
  return float(histogram.size()) * bin;
}

}  // namespace

NoiseHistograms::NoiseHistograms()
    : second_difference(std::size_t(kSecondDifferenceBins), 0), depth(std::size_t(kDepthBins), 0) {}

DepthNoise measure_depth_noise(const Image<float>& depth, NoiseHistograms* h) {
  std::fill(h->second_difference.begin(), h->second_difference.end(), 0);
  std::fill(h->depth.begin(), h->depth.end(), 0);
  DepthNoise out;
  int depths = 0;
  for (int j = 0; j < depth.height; j += 2) {
    const float* row = &depth.pixels[std::size_t(j) * std::size_t(depth.width)];
    for (int i = 1; i + 1 < depth.width; ++i) {
      const float z = row[i];
      if (!(z > 0)) continue;
      ++h->depth[std::size_t(std::min(kDepthBins - 1, int(z / kDepthBinMm)))];
      ++depths;
      if (!(row[i - 1] > 0) || !(row[i + 1] > 0)) continue;
      const float s = std::abs(row[i - 1] - 2 * z + row[i + 1]);
      ++h->second_difference[std::size_t(std::min(kSecondDifferenceBins - 1, int(s / kSecondDifferenceBinMm)))];
      ++out.samples;
    }
  }
  out.depth_mm = depths > 0 ? median_of(h->depth, depths, kDepthBinMm) : kFallbackDepthMm;
  out.sigma_mm = out.samples >= kMinNoiseSamples
                     ? trimmed_mean_of(h->second_difference, out.samples, kKeptShare, kSecondDifferenceBinMm) /
                           kTrimmedMeanOfSigma
                     : kFallbackSigmaMm;
  return out;
}

LocateConfig with_model_thresholds(const LocateConfig& user, float d) {
  LocateConfig cfg = user;
  if (cfg.normal_window_mm <= 0) cfg.normal_window_mm = kNormalWindowOfD * d;
  if (cfg.hole_fill_mm <= 0) cfg.hole_fill_mm = kHoleFillOfD * d;
  // Until a frame is measured: the fallback noise.
  set_frame_thresholds(user, d, DepthNoise{kFallbackSigmaMm, kFallbackDepthMm, 0}, Intrinsics{}, &cfg);
  return cfg;
}

void set_frame_thresholds(const LocateConfig& user, float d, const DepthNoise& noise, const Intrinsics& camera,
                          LocateConfig* cfg) {
  const double sigma = std::min(kMaxSigmaMm, double(noise.sigma_mm));
  if (user.continuity_step_max_mm <= 0)
    cfg->continuity_step_max_mm =
        std::max(kContinuityStepOfSigma * sigma, kContinuityStepMinCells * cfg->zbuffer_pixel_mm);
  if (user.verify_tolerance_mm <= 0)
    cfg->verify_tolerance_mm = std::max(kVerifyToleranceOfSigma * sigma, kVerifyToleranceMinMm);
  else if (user.raise_to_noise)
    cfg->verify_tolerance_mm = std::max(user.verify_tolerance_mm, kVerifyToleranceOfSigma * sigma);
  if (user.refine_inlier_mm <= 0)
    cfg->refine_inlier_mm = std::max(kRefineInlierOfSigma * sigma, kRefineInlierOfD * double(d));
  cfg->residual_noise_floor_mm = user.raise_to_noise ? kResidualOfSigma * sigma : 0.0;
  cfg->frame_sigma_mm = sigma;
  cfg->frame_noise_mm = noise.sigma_mm;
  if (user.normal_window_mm <= 0) {
    const double footprint_mm = double(noise.depth_mm) / std::max(1.0, camera.fx);
    const double sample_mm = std::max(cfg->zbuffer_pixel_mm, footprint_mm);
    cfg->normal_window_mm = std::max({kNormalWindowOfD * d, kNormalWindowMinFootprints * footprint_mm,
                                      std::sqrt(kNormalWindowOfNoise * sigma * sample_mm)});
  }
}

bool derives_from_frame(const LocateConfig& user) {
  return user.continuity_step_max_mm <= 0 || user.verify_tolerance_mm <= 0 || user.refine_inlier_mm <= 0 ||
         user.normal_window_mm <= 0 || user.raise_to_noise || user.pick_min_relief_sigmas > 0;
}

float max_refine_inlier_mm(const LocateConfig& user, float d) {
  if (user.refine_inlier_mm > 0) return float(user.refine_inlier_mm);
  return float(std::max(kRefineInlierOfSigma * kMaxSigmaMm, kRefineInlierOfD * double(d)));
}

LocateConfig surface_retry_config(const LocateConfig& cfg, float tube_d_mm) {
  LocateConfig out = cfg;
  out.match_surface = true;
  out.ridge_cell_mm = std::max(cfg.ridge_cell_mm, cfg.retry_surface_cell_of_d * tube_d_mm);
  out.icp_probe_cell_mm = std::max(cfg.icp_probe_cell_mm, 2 * out.ridge_cell_mm);
  return out;
}

}  // namespace pipeloc
