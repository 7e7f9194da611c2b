// Pictures for people: depth shaded in colour, with lines, dots and region tints drawn on top.
#pragma once

#include "core/image.hpp"
#include "io/png.hpp"

namespace pipeloc {

// Between the 2nd and 98th percentile of valid depth: rainbow near = red, far = blue; grey near =
// bright, far = dark. No reading = black.
enum class DepthShade { rainbow, grey };
Image<Rgb> shade_depth(const Image<float>& depth_mm, DepthShade shade = DepthShade::rainbow);

void draw_line(Image<Rgb>* img, double x0, double y0, double x1, double y1, Rgb color, int thickness = 1);
void draw_dot(Image<Rgb>* img, double x, double y, int radius, Rgb color);
void tint(Image<Rgb>* img, int x, int y, Rgb color, float alpha);

}  // namespace pipeloc
