// PNG in and out through libpng: 16-bit depth, 8-bit RGB overlays.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "core/image.hpp"

namespace pipeloc {

struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

// Reads a single-channel 16-bit PNG (raw sensor units). Throws IoError naming the file and the
// problem (missing, not PNG, truncated, wrong bit depth or channels).
Image<std::uint16_t> read_depth_png(const std::string& path);
void write_depth_png(const std::string& path, const Image<std::uint16_t>& depth);
void write_rgb_png(const std::string& path, const Image<Rgb>& image);
// The same PNG as bytes (for the status page).
std::vector<std::uint8_t> encode_rgb_png(const Image<Rgb>& image);

}  // namespace pipeloc
