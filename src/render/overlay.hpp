// Pictures for people: depth shaded in colour, with lines, dots and region tints drawn on top.
#pragma once

#include "core/image.hpp"
#include "io/png.hpp"

namespace pipeloc {

// Near = red, far = blue (between the 2nd and 98th percentile of valid depth); no reading = black.
Image<Rgb> shade_depth(const Image<float>& depth_mm);

void draw_line(Image<Rgb>* img, double x0, double y0, double x1, double y1, Rgb color, int thickness = 1);
void draw_dot(Image<Rgb>* img, double x, double y, int radius, Rgb color);
void tint(Image<Rgb>* img, int x, int y, Rgb color, float alpha);

}  // namespace pipeloc
