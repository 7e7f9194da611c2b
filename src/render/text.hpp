// A 3x5 pixel font for digits and a few signs, so charts can carry their numbers.
#pragma once

#include <string>

#include "core/image.hpp"
#include "io/png.hpp"

namespace pipeloc {

// Draws `text` (digits, '.', '-', '%', 'm', 's', 'p', space) with its top-left at (x, y), each
// font pixel `scale` image pixels wide. Other characters leave a gap.
void draw_text(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale = 2);

}  // namespace pipeloc
