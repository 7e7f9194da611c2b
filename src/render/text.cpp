#include "render/text.hpp"

namespace pipeloc {
namespace {

// Rows top to bottom, 3 bits each (bit 2 = left column).
struct Glyph {
  char c;
  unsigned char rows[5];
};
constexpr Glyph kGlyphs[] = {
    {'0', {7, 5, 5, 5, 7}}, {'1', {2, 6, 2, 2, 7}}, {'2', {7, 1, 7, 4, 7}}, {'3', {7, 1, 7, 1, 7}},
    {'4', {5, 5, 7, 1, 1}}, {'5', {7, 4, 7, 1, 7}}, {'6', {7, 4, 7, 5, 7}}, {'7', {7, 1, 1, 1, 1}},
    {'8', {7, 5, 7, 5, 7}}, {'9', {7, 5, 7, 1, 7}}, {'.', {0, 0, 0, 0, 2}}, {'-', {0, 0, 7, 0, 0}},
    {'%', {5, 1, 2, 4, 5}}, {'m', {0, 0, 7, 7, 5}}, {'s', {0, 3, 6, 1, 6}}, {'p', {0, 7, 5, 7, 4}},
};

}  // namespace

void draw_text(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale) {
  for (const char ch : text) {
    for (const Glyph& g : kGlyphs) {
      if (g.c != ch) continue;
      for (int r = 0; r < 5; ++r)
        for (int c = 0; c < 3; ++c)
          if (g.rows[r] & (4 >> c))
            for (int dy = 0; dy < scale; ++dy)
              for (int dx = 0; dx < scale; ++dx) {
                const int px = x + c * scale + dx, py = y + r * scale + dy;
                if (img->inside(px, py)) img->at(px, py) = color;
              }
    }
    x += 4 * scale;
  }
}

}  // namespace pipeloc
