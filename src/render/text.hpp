// A 3x5 pixel font for digits, capitals and a few signs, so charts and overlays carry their words.
#pragma once

#include <string>

#include "core/image.hpp"
#include "io/png.hpp"

namespace pipeloc {

// Draws `text` (digits, A-Z, 'm', 's', 'p', other lower case as capitals, . - % : # / ( ) = + , < >
// and space) with its top-left at (x, y), each font pixel `scale` image pixels wide; a character
// is 4 * scale wide. Other characters leave a gap.
void draw_text(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale = 2);
// The same on a dark box one font pixel wider all round, readable over any background.
void draw_label(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale = 2);

}  // namespace pipeloc
