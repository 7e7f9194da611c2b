// A row-major image of fixed size; the buffer is allocated once by its owner.
#pragma once

#include <cstddef>
#include <vector>

namespace pipeloc {

template <typename T>
struct Image {
  int width = 0;
  int height = 0;
  std::vector<T> pixels;

  Image() = default;
  Image(int w, int h, T fill = T{}) : width(w), height(h), pixels(std::size_t(w) * h, fill) {}

  void resize(int w, int h, T fill = T{}) {
    width = w;
    height = h;
    pixels.assign(std::size_t(w) * h, fill);
  }
  void fill(T value) { std::fill(pixels.begin(), pixels.end(), value); }
  bool inside(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
  T& at(int x, int y) { return pixels[std::size_t(y) * width + x]; }
  const T& at(int x, int y) const { return pixels[std::size_t(y) * width + x]; }
};

}  // namespace pipeloc
