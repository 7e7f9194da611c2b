#include "sim/sensor.hpp"

#include <cmath>

namespace pipeloc {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Incidence angle (degrees) between the surface normal and the ray to the camera.
double incidence_deg(const Eigen::Vector3f& normal, const Eigen::Vector3d& point) {
  const double c = std::abs(normal.cast<double>().dot(-point.normalized()));
  return std::acos(std::min(1.0, c)) / kDeg;
}

}  // namespace

Image<float> apply_sensor_model(const DepthTarget& cam, const DepthTarget& proj, const Intrinsics& k,
                                const SensorModel& m, int pipe_labels, std::mt19937& rng) {
  const int w = cam.z_mm.width, h = cam.z_mm.height;
  Image<float> out(w, h, 0.0f);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double fb = k.fx * m.baseline_mm;

  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // Lateral noise: the pixel reports the surface a fraction of a pixel away.
      const int sx = std::clamp(int(std::lround(x + gauss(rng) * m.lateral_sigma_px)), 0, w - 1);
      const int sy = std::clamp(int(std::lround(y + gauss(rng) * m.lateral_sigma_px)), 0, h - 1);
      const float z = cam.z_mm.at(sx, sy);
      if (z <= 0 || z < m.min_range_mm || z > m.max_range_mm) continue;
      const Eigen::Vector3d p = k.unproject(sx, sy, z);

      const double theta = incidence_deg(cam.normal.at(sx, sy), p);
      const double grazing = m.grazing_min_deg + uniform(rng) * (m.grazing_max_deg - m.grazing_min_deg);
      if (theta > grazing) continue;

      // Projector shadow: the pattern cannot reach a point the projector does not see first.
      const Eigen::Vector3d pp = p - Eigen::Vector3d(m.baseline_mm, 0, 0);
      const Eigen::Vector2d uv = k.project(pp);
      const int px = int(std::lround(uv.x())), py = int(std::lround(uv.y()));
      if (!proj.z_mm.inside(px, py)) continue;
      const float zp = proj.z_mm.at(px, py);
      if (zp <= 0 || pp.z() > zp + m.shadow_tolerance_mm + m.depth_step_mm(zp, k.fx)) continue;

      if (uniform(rng) < m.dropout_prob) continue;

      double sigma = m.axial_sigma_mm(z);
      if (theta > m.noisy_incidence_deg)
        sigma *= std::cos(m.noisy_incidence_deg * kDeg) / std::cos(theta * kDeg);
      const double noisy = z + gauss(rng) * sigma;
      // Disparity is measured in 1/8 px: depth comes in steps.
      const double disparity = std::round(fb / noisy / m.disparity_step_px) * m.disparity_step_px;
      if (disparity <= 0) continue;
      out.at(x, y) = float(fb / disparity);
    }
  }

  // Specular highlights: blobs of missing depth where a pipe's ridge faces the camera.
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const int label = cam.label.at(x, y);
      if (label < 0 || label >= pipe_labels || cam.z_mm.at(x, y) <= 0) continue;
      const Eigen::Vector3d p = k.unproject(x, y, cam.z_mm.at(x, y));
      if (incidence_deg(cam.normal.at(x, y), p) > m.specular_max_incidence_deg) continue;
      if (uniform(rng) >= m.specular_seed_prob) continue;
      const int r = 1 + int(uniform(rng) * m.specular_max_radius_px);
      for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
          if (dx * dx + dy * dy <= r * r && out.inside(x + dx, y + dy) &&
              cam.label.at(x + dx, y + dy) == label)
            out.at(x + dx, y + dy) = 0;
    }
  }
  return out;
}

Image<std::uint16_t> to_raw_depth(const Image<float>& depth_mm, double depth_scale) {
  Image<std::uint16_t> raw(depth_mm.width, depth_mm.height, 0);
  for (std::size_t i = 0; i < raw.pixels.size(); ++i) {
    const double v = std::round(depth_mm.pixels[i] / depth_scale);
    raw.pixels[i] = std::uint16_t(std::clamp(v, 0.0, 65535.0));
  }
  return raw;
}

}  // namespace pipeloc
