// A 3x5 pixel font for digits, capitals and a few signs, so charts and overlays carry their words.
#pragma once

#include <Eigen/Core>
#include <string>

#include "core/image.hpp"
#include "io/png.hpp"
#include "render/raster.hpp"

namespace pipeloc {

// Draws `text` (digits, A-Z, 'm', 's', 'p', other lower case as capitals, . - % : # / ( ) = + , < >
// and space) with its top-left at (x, y), each font pixel `scale` image pixels wide; a character
// is 4 * scale wide. Other characters leave a gap.
void draw_text(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale = 2);
// The same on a dark box one font pixel wider all round, readable over any background.
void draw_label(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale = 2);
// Where a label asked at (x, y) is drawn so that all of it can be read: moved wholly into a width
// x height image (a pose at the image's edge has its centre near or beyond it), then off
// `keep_clear` (the legend, drawn over it) by the shorter of the moves below or right of it that
// stays in the image. Returns the top-left to pass to draw_label.
Eigen::Vector2i place_label(int x, int y, const std::string& text, int width, int height,
                            const PixelBox& keep_clear, int scale = 2);

}  // namespace pipeloc
