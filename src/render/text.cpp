#include "render/text.hpp"

#include <algorithm>

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
    {'A', {2, 5, 7, 5, 5}}, {'B', {6, 5, 6, 5, 6}}, {'C', {3, 4, 4, 4, 3}}, {'D', {6, 5, 5, 5, 6}},
    {'E', {7, 4, 6, 4, 7}}, {'F', {7, 4, 6, 4, 4}}, {'G', {3, 4, 5, 5, 3}}, {'H', {5, 5, 7, 5, 5}},
    {'I', {7, 2, 2, 2, 7}}, {'J', {1, 1, 1, 5, 2}}, {'K', {5, 5, 6, 5, 5}}, {'L', {4, 4, 4, 4, 7}},
    {'M', {5, 7, 7, 5, 5}}, {'N', {6, 5, 5, 5, 5}}, {'O', {2, 5, 5, 5, 2}}, {'P', {6, 5, 6, 4, 4}},
    {'Q', {2, 5, 5, 6, 3}}, {'R', {6, 5, 6, 5, 5}}, {'S', {3, 4, 2, 1, 6}}, {'T', {7, 2, 2, 2, 2}},
    {'U', {5, 5, 5, 5, 7}}, {'V', {5, 5, 5, 5, 2}}, {'W', {5, 5, 7, 7, 5}}, {'X', {5, 5, 2, 5, 5}},
    {'Y', {5, 5, 2, 2, 2}}, {'Z', {7, 1, 2, 4, 7}}, {':', {0, 2, 0, 2, 0}}, {'#', {5, 7, 5, 7, 5}},
    {'/', {1, 1, 2, 4, 4}}, {'(', {1, 2, 2, 2, 1}}, {')', {4, 2, 2, 2, 4}}, {'=', {0, 7, 0, 7, 0}},
    {'+', {0, 2, 7, 2, 0}}, {',', {0, 0, 0, 2, 4}}, {'<', {1, 2, 4, 2, 1}}, {'>', {4, 2, 1, 2, 4}},
};

const Glyph* glyph_of(char ch) {
  for (const Glyph& g : kGlyphs)
    if (g.c == ch) return &g;
  // Lower case without a glyph of its own is drawn in capitals.
  if (ch >= 'a' && ch <= 'z') return glyph_of(char(ch - 'a' + 'A'));
  return nullptr;
}

}  // namespace

void draw_text(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale) {
  for (const char ch : text) {
    if (const Glyph* g = glyph_of(ch))
      for (int r = 0; r < 5; ++r)
        for (int c = 0; c < 3; ++c)
          if (g->rows[r] & (4 >> c))
            for (int dy = 0; dy < scale; ++dy)
              for (int dx = 0; dx < scale; ++dx) {
                const int px = x + c * scale + dx, py = y + r * scale + dy;
                if (img->inside(px, py)) img->at(px, py) = color;
              }
    x += 4 * scale;
  }
}

void draw_label(Image<Rgb>* img, int x, int y, const std::string& text, Rgb color, int scale) {
  const int w = int(text.size()) * 4 * scale + scale, h = 7 * scale;
  for (int py = y - scale; py < y - scale + h; ++py)
    for (int px = x - scale; px < x - scale + w; ++px)
      if (img->inside(px, py)) img->at(px, py) = {20, 20, 20};
  draw_text(img, x, y, text, color, scale);
}

Eigen::Vector2i place_label(int x, int y, const std::string& text, int width, int height,
                            const PixelBox& keep_clear, int scale) {
  // The dark box spans [x - scale, x - scale + w) x [y - scale, y - scale + h), as draw_label draws it.
  const int w = int(text.size()) * 4 * scale + scale, h = 7 * scale;
  const int x_max = std::max(scale, width - w + scale), y_max = std::max(scale, height - h + scale);
  x = std::clamp(x, scale, x_max), y = std::clamp(y, scale, y_max);
  const bool under = !keep_clear.empty() && x - scale <= keep_clear.x1 &&
                     x - scale + w - 1 >= keep_clear.x0 && y - scale <= keep_clear.y1 &&
                     y - scale + h - 1 >= keep_clear.y0;
  if (!under) return {x, y};
  const int below = keep_clear.y1 + 1 + scale, right = keep_clear.x1 + 1 + scale;
  const bool below_fits = below <= y_max, right_fits = right <= x_max;
  if (below_fits && (!right_fits || below - y <= right - x)) return {x, below};
  if (right_fits) return {right, y};
  return {x, y};
}

}  // namespace pipeloc
