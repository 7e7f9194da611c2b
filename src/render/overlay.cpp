#include "render/overlay.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pipeloc {
namespace {

// A short rainbow: red (near) -> yellow -> green -> cyan -> blue (far).
Rgb ramp(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  const float stops[5][3] = {{230, 30, 20}, {250, 200, 30}, {60, 200, 80}, {40, 190, 220}, {30, 70, 200}};
  const float s = t * 4;
  const int i = std::min(3, int(s));
  const float f = s - float(i);
  Rgb c;
  c.r = std::uint8_t(stops[i][0] + f * (stops[i + 1][0] - stops[i][0]));
  c.g = std::uint8_t(stops[i][1] + f * (stops[i + 1][1] - stops[i][1]));
  c.b = std::uint8_t(stops[i][2] + f * (stops[i + 1][2] - stops[i][2]));
  return c;
}

}  // namespace

Image<Rgb> shade_depth(const Image<float>& depth, DepthShade shade) {
  Image<Rgb> out(depth.width, depth.height);
  std::vector<float> valid;
  valid.reserve(depth.pixels.size());
  for (float z : depth.pixels)
    if (z > 0) valid.push_back(z);
  if (valid.empty()) return out;
  const auto at = [&](double q) {
    auto it = valid.begin() + std::ptrdiff_t(q * double(valid.size() - 1));
    std::nth_element(valid.begin(), it, valid.end());
    return *it;
  };
  const float near = at(0.02), far = std::max(at(0.98), near + 1.0f);
  for (std::size_t i = 0; i < depth.pixels.size(); ++i) {
    if (!(depth.pixels[i] > 0)) continue;
    const float t = (depth.pixels[i] - near) / (far - near);
    if (shade == DepthShade::rainbow) {
      out.pixels[i] = ramp(t);
      continue;
    }
    const auto g = std::uint8_t(235 - 195 * std::clamp(t, 0.0f, 1.0f));
    out.pixels[i] = {g, g, g};
  }
  return out;
}

void tint(Image<Rgb>* img, int x, int y, Rgb c, float a) {
  if (!img->inside(x, y)) return;
  Rgb& p = img->at(x, y);
  p.r = std::uint8_t(p.r * (1 - a) + c.r * a);
  p.g = std::uint8_t(p.g * (1 - a) + c.g * a);
  p.b = std::uint8_t(p.b * (1 - a) + c.b * a);
}

void draw_dot(Image<Rgb>* img, double x, double y, int radius, Rgb color) {
  const int cx = int(std::lround(x)), cy = int(std::lround(y));
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx)
      if (dx * dx + dy * dy <= radius * radius && img->inside(cx + dx, cy + dy))
        img->at(cx + dx, cy + dy) = color;
}

void draw_line(Image<Rgb>* img, double x0, double y0, double x1, double y1, Rgb color, int thickness) {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int steps = std::max(1, int(std::ceil(len * 2)));
  if (steps > 100000) return;  // a line that long is off-screen nonsense
  for (int s = 0; s <= steps; ++s) {
    const double t = double(s) / steps;
    draw_dot(img, x0 + t * (x1 - x0), y0 + t * (y1 - y0), thickness / 2, color);
  }
}

}  // namespace pipeloc
