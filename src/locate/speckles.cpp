#include "locate/speckles.hpp"

#include <algorithm>

namespace pipeloc {

int remove_speckles(const Image<float>& depth, float step_mm, Image<float>* out) {
  const int w = depth.width, h = depth.height, r = kSpeckleReachPx;
  if (out->width != w || out->height != h) out->resize(w, h, 0.0f);
  int removed = 0;
  for (int y = 0; y < h; ++y) {
    const int y0 = std::max(0, y - r), y1 = std::min(h - 1, y + r);
    for (int x = 0; x < w; ++x) {
      const float z = depth.at(x, y);
      out->at(x, y) = z;
      if (!(z > 0)) continue;
      // Kept once one reading is seen not farther than z + step and one not nearer than z - step
      // (most often both at once: the first reading looked at, within the step).
      bool not_all_farther = false, not_all_nearer = false, any = false;
      const int x0 = std::max(0, x - r), x1 = std::min(w - 1, x + r);
      for (int v = y0; v <= y1 && !(not_all_farther && not_all_nearer); ++v)
        for (int u = x0; u <= x1 && !(not_all_farther && not_all_nearer); ++u) {
          const float n = depth.at(u, v);
          if ((u == x && v == y) || !(n > 0)) continue;
          any = true;
          not_all_farther = not_all_farther || n <= z + step_mm;
          not_all_nearer = not_all_nearer || n >= z - step_mm;
        }
      if (any && !(not_all_farther && not_all_nearer)) out->at(x, y) = 0.0f, ++removed;
    }
  }
  return removed;
}

}  // namespace pipeloc
