// The structured-light sensor model of DESIGN.md (Kinect v1 / PrimeSense published figures), and
// an active-stereo one (RealSense D4xx class) with the same parts and other figures.
#pragma once

#include <cstdint>
#include <random>
#include <string>

#include "core/camera.hpp"
#include "render/raster.hpp"

namespace pipeloc {

struct SensorModel {
  double baseline_mm = 75;                                      // projector beside the camera along +x
  double disparity_step_px = 0.125;                             // 1/8 px: depth steps of z^2 / (8 f b)
  double sigma_a_mm = 1.2, sigma_b_mm = 1.9, sigma_z0_m = 0.4;  // axial: a + b (z - z0)^2
  double lateral_sigma_px = 0.8;
  double noisy_incidence_deg = 60;                    // axial noise grows beyond this
  double grazing_min_deg = 70, grazing_max_deg = 80;  // no return past a threshold in this range
  double shadow_tolerance_mm = 3;
  double specular_max_incidence_deg = 12;  // ridge pixels facing the camera can glint
  double specular_seed_prob = 0.012;
  int specular_max_radius_px = 3;
  double dropout_prob = 0.003;
  double min_range_mm = 500, max_range_mm = 3500;
  // Active stereo: axial noise from the disparity noise, sigma_z = z^2 sigma_d / (f b), instead of
  // the a + b (z - z0)^2 fit (0: use the fit).
  double disparity_sigma_px = 0;
  // Flying pixels: where the clean depth jumps by more than flying_edge_mm within one pixel, this
  // share of pixels reports a blend of fore- and background (stereo matching across the edge).
  double flying_pixel_prob = 0, flying_edge_mm = 10;

  double axial_sigma_mm(double z_mm, double f_px) const {
    if (disparity_sigma_px > 0) return z_mm * z_mm * disparity_sigma_px / (f_px * baseline_mm);
    const double dz = z_mm / 1000.0 - sigma_z0_m;
    return sigma_a_mm + sigma_b_mm * dz * dz;
  }
  double depth_step_mm(double z_mm, double f_px) const {
    return z_mm * z_mm * disparity_step_px / (f_px * baseline_mm);
  }
};

// The sensor models by name: "kinect" (the default above) or "stereo" (RealSense D4xx class:
// b = 50 mm, 0.08 px disparity noise, 1/32 px subpixel steps, flying pixels, usable from 0.3 m).
// Throws std::invalid_argument for another name.
SensorModel sensor_model(const std::string& name);

// What stays fixed while the scene is still: the clean depth and labels, and per pixel the
// incidence angle of the ray and whether the projector's pattern reaches it.
struct SensorView {
  enum Reach : std::uint8_t { none, shadowed, lit };  // none: nothing there, or out of range
  Image<float> z_mm;
  Image<int> label;
  Image<float> incidence_deg;
  Image<std::uint8_t> reach;
};
SensorView prepare_sensor_view(const DepthTarget& camera, const DepthTarget& projector, const Intrinsics& k,
                               const SensorModel& model);
// One noisy frame of a still scene into out_mm (sized like the view); allocates nothing.
void apply_sensor_noise(const SensorView& view, const Intrinsics& k, const SensorModel& model,
                        int pipe_labels, std::mt19937& rng, Image<float>* out_mm);

// Turns a clean render (camera view) into what the sensor reports, in mm (0 = no reading).
// `projector` is the same scene rendered from the projector's position (camera + baseline x).
// Pipe pixels are those with a label in [0, pipe_labels).
Image<float> apply_sensor_model(const DepthTarget& camera, const DepthTarget& projector, const Intrinsics& k,
                                const SensorModel& model, int pipe_labels, std::mt19937& rng);

// Depth in mm to raw 16-bit PNG units.
Image<std::uint16_t> to_raw_depth(const Image<float>& depth_mm, double depth_scale);
// The same units, kept in mm: the depth as a sensor reports it (in place).
void round_to_raw_units(Image<float>* depth_mm, double depth_scale);

}  // namespace pipeloc
