#include "sim/sensor.hpp"

#include <cmath>
#include <stdexcept>

namespace pipeloc {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Incidence angle (degrees) between the surface normal and the ray to the camera.
double incidence_deg(const Eigen::Vector3f& normal, const Eigen::Vector3d& point) {
  const double c = std::abs(normal.cast<double>().dot(-point.normalized()));
  return std::acos(std::min(1.0, c)) / kDeg;
}

}  // namespace

SensorModel sensor_model(const std::string& name) {
  SensorModel m;
  if (name == "kinect") return m;
  if (name != "stereo") throw std::invalid_argument("sensor '" + name + "': expected kinect or stereo");
  // RealSense D4xx class (Intel's depth-quality figures): RMS disparity error about 0.08 px,
  // 1/32 px subpixel resolution, 50 mm baseline, minimum range about 0.3 m.
  m.baseline_mm = 50;
  m.disparity_step_px = 1.0 / 32;
  m.disparity_sigma_px = 0.08;
  m.min_range_mm = 300;
  m.max_range_mm = 3000;
  m.lateral_sigma_px = 0.5;
  m.flying_pixel_prob = 0.5;
  return m;
}

SensorView prepare_sensor_view(const DepthTarget& cam, const DepthTarget& proj, const Intrinsics& k,
                               const SensorModel& m) {
  const int w = cam.z_mm.width, h = cam.z_mm.height;
  SensorView view;
  view.z_mm = cam.z_mm;
  view.label = cam.label;
  view.incidence_deg.resize(w, h, 0.0f);
  view.reach.resize(w, h, SensorView::none);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float z = cam.z_mm.at(x, y);
      if (z <= 0) continue;
      const Eigen::Vector3d p = k.unproject(x, y, z);
      view.incidence_deg.at(x, y) = float(incidence_deg(cam.normal.at(x, y), p));
      if (z < m.min_range_mm || z > m.max_range_mm) continue;
      // Projector shadow: the pattern cannot reach a point the projector does not see first.
      view.reach.at(x, y) = SensorView::shadowed;
      const Eigen::Vector3d pp = p - Eigen::Vector3d(m.baseline_mm, 0, 0);
      const Eigen::Vector2d uv = k.project(pp);
      const int px = int(std::lround(uv.x())), py = int(std::lround(uv.y()));
      if (!proj.z_mm.inside(px, py)) continue;
      const float zp = proj.z_mm.at(px, py);
      if (zp <= 0 || pp.z() > zp + m.shadow_tolerance_mm + m.depth_step_mm(zp, k.fx)) continue;
      view.reach.at(x, y) = SensorView::lit;
    }
  }
  return view;
}

void apply_sensor_noise(const SensorView& view, const Intrinsics& k, const SensorModel& m, int pipe_labels,
                        std::mt19937& rng, Image<float>* out_mm) {
  const int w = view.z_mm.width, h = view.z_mm.height;
  out_mm->fill(0.0f);
  Image<float>& out = *out_mm;
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double fb = k.fx * m.baseline_mm;
  const double cos_noisy = std::cos(m.noisy_incidence_deg * kDeg);

  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // Lateral noise: the pixel reports the surface a fraction of a pixel away.
      const int sx = std::clamp(int(std::lround(x + gauss(rng) * m.lateral_sigma_px)), 0, w - 1);
      const int sy = std::clamp(int(std::lround(y + gauss(rng) * m.lateral_sigma_px)), 0, h - 1);
      const std::uint8_t reach = view.reach.at(sx, sy);
      if (reach == SensorView::none) continue;
      const float theta = view.incidence_deg.at(sx, sy);
      const double grazing = m.grazing_min_deg + uniform(rng) * (m.grazing_max_deg - m.grazing_min_deg);
      if (theta > grazing || reach == SensorView::shadowed) continue;
      if (uniform(rng) < m.dropout_prob) continue;

      const double z = view.z_mm.at(sx, sy);
      double sigma = m.axial_sigma_mm(z, k.fx);
      if (theta > m.noisy_incidence_deg) sigma *= cos_noisy / std::cos(theta * kDeg);
      const double noisy = z + gauss(rng) * sigma;
      // Disparity is measured in 1/8 px: depth comes in steps.
      const double disparity = std::round(fb / noisy / m.disparity_step_px) * m.disparity_step_px;
      if (disparity <= 0) continue;
      out.at(x, y) = float(fb / disparity);
    }
  }

  // Flying pixels: at a depth edge the matcher blends the two sides.
  if (m.flying_pixel_prob > 0) {
    for (int y = 1; y + 1 < h; ++y) {
      for (int x = 1; x + 1 < w; ++x) {
        if (out.at(x, y) <= 0) continue;
        float lo = view.z_mm.at(x, y), hi = lo;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const float z = view.z_mm.at(x + dx, y + dy);
            if (z > 0) lo = std::min(lo, z), hi = std::max(hi, z);
          }
        if (hi - lo <= m.flying_edge_mm || uniform(rng) >= m.flying_pixel_prob) continue;
        out.at(x, y) = float(lo + uniform(rng) * (hi - lo));
      }
    }
  }

  // Specular highlights: blobs of missing depth where a pipe's ridge faces the camera.
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int label = view.label.at(x, y);
      if (label < 0 || label >= pipe_labels || view.z_mm.at(x, y) <= 0) continue;
      if (view.incidence_deg.at(x, y) > m.specular_max_incidence_deg) continue;
      if (uniform(rng) >= m.specular_seed_prob) continue;
      const int r = 1 + int(uniform(rng) * m.specular_max_radius_px);
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (dx * dx + dy * dy <= r * r && out.inside(x + dx, y + dy) &&
              view.label.at(x + dx, y + dy) == label)
            out.at(x + dx, y + dy) = 0;
    }
  }
}

Image<float> apply_sensor_model(const DepthTarget& cam, const DepthTarget& proj, const Intrinsics& k,
                                const SensorModel& m, int pipe_labels, std::mt19937& rng) {
  Image<float> out(cam.z_mm.width, cam.z_mm.height, 0.0f);
  apply_sensor_noise(prepare_sensor_view(cam, proj, k, m), k, m, pipe_labels, rng, &out);
  return out;
}

namespace {
double raw_units(float mm, double depth_scale) {
  return std::clamp(std::round(mm / depth_scale), 0.0, 65535.0);
}
}  // namespace

Image<std::uint16_t> to_raw_depth(const Image<float>& depth_mm, double depth_scale) {
  Image<std::uint16_t> raw(depth_mm.width, depth_mm.height, 0);
  for (std::size_t i = 0; i < raw.pixels.size(); ++i)
    raw.pixels[i] = std::uint16_t(raw_units(depth_mm.pixels[i], depth_scale));
  return raw;
}

void round_to_raw_units(Image<float>* depth_mm, double depth_scale) {
  for (float& z : depth_mm->pixels) z = float(raw_units(z, depth_scale) * depth_scale);
}

}  // namespace pipeloc
