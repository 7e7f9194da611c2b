#include "io/png.hpp"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <memory>
#include <vector>

namespace pipeloc {
namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// libpng reports errors through longjmp; the message is kept so the exception can name it.
struct ErrorSink {
  std::string message;
};

void on_error(png_structp png, png_const_charp msg) {
  static_cast<ErrorSink*>(png_get_error_ptr(png))->message = msg;
  png_longjmp(png, 1);
}
void on_warning(png_structp, png_const_charp) {}

// Runs f with libpng's error jump armed; false if libpng reported an error. f must not own
// objects with destructors (longjmp skips them).
template <typename F>
bool guarded(png_structp png, F&& f) {
  if (setjmp(png_jmpbuf(png))) return false;
  f();
  return true;
}

}  // namespace

Image<std::uint16_t> read_depth_png(const std::string& path) {
  File file(std::fopen(path.c_str(), "rb"));
  if (!file) throw IoError("depth PNG '" + path + "': cannot open file");
  unsigned char signature[8] = {};
  if (std::fread(signature, 1, 8, file.get()) != 8 || png_sig_cmp(signature, 0, 8) != 0)
    throw IoError("depth PNG '" + path + "': not a PNG file");
  ErrorSink sink;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &sink, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw IoError("depth PNG '" + path + "': out of memory");
  }
  Image<std::uint16_t> depth;
  std::vector<png_bytep> rows;
  std::string problem;
  const bool ok = guarded(png, [&] {
    png_init_io(png, file.get());
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);
    const int bit_depth = png_get_bit_depth(png, info);
    const int color = png_get_color_type(png, info);
    const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    if (bit_depth != 16 || color != PNG_COLOR_TYPE_GRAY) {
      problem = "expected 16-bit single-channel depth, got " + std::to_string(bit_depth) +
                "-bit colour type " + std::to_string(color);
    } else if (w == 0 || h == 0 || w > 8192 || h > 8192) {
      problem = "unreasonable size " + std::to_string(w) + "x" + std::to_string(h);
    } else {
      png_set_swap(png);  // PNG stores 16-bit big-endian
      depth.resize(int(w), int(h));
      rows.resize(h);
      for (png_uint_32 y = 0; y < h; ++y) rows[y] = reinterpret_cast<png_bytep>(&depth.at(0, int(y)));
      png_read_image(png, rows.data());
      png_read_end(png, nullptr);
    }
  });
  if (!ok) problem = sink.message.empty() ? "corrupt data" : sink.message;
  png_destroy_read_struct(&png, &info, nullptr);
  if (!problem.empty()) throw IoError("depth PNG '" + path + "': " + problem);
  return depth;
}

namespace {

void append_to_vector(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + length);
}

// Into the file at `path`, or into `memory` when it is given (path then only names it in errors).
void write_png(const std::string& path, int width, int height, int bit_depth, int color, int bytes_per_row,
               const std::uint8_t* data, bool swap16, std::vector<std::uint8_t>* memory = nullptr) {
  File file(memory ? nullptr : std::fopen(path.c_str(), "wb"));
  if (!memory && !file) throw IoError("PNG '" + path + "': cannot open for writing");
  ErrorSink sink;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    throw IoError("PNG '" + path + "': out of memory");
  }
  std::vector<png_bytep> rows(height);
  for (int y = 0; y < height; ++y) rows[y] = const_cast<png_bytep>(data + std::size_t(y) * bytes_per_row);
  const bool ok = guarded(png, [&] {
    if (memory)
      png_set_write_fn(png, memory, append_to_vector, nullptr);
    else
      png_init_io(png, file.get());
    png_set_IHDR(png, info, width, height, bit_depth, color, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 3);
    png_write_info(png, info);
    if (swap16) png_set_swap(png);
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
  });
  png_destroy_write_struct(&png, &info);
  if (!ok) throw IoError("PNG '" + path + "': " + sink.message);
}

}  // namespace

void write_depth_png(const std::string& path, const Image<std::uint16_t>& depth) {
  write_png(path, depth.width, depth.height, 16, PNG_COLOR_TYPE_GRAY, depth.width * 2,
            reinterpret_cast<const std::uint8_t*>(depth.pixels.data()), true);
}

void write_rgb_png(const std::string& path, const Image<Rgb>& image) {
  static_assert(sizeof(Rgb) == 3, "Rgb must be packed");
  write_png(path, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, image.width * 3,
            reinterpret_cast<const std::uint8_t*>(image.pixels.data()), false);
}

std::vector<std::uint8_t> encode_rgb_png(const Image<Rgb>& image) {
  std::vector<std::uint8_t> png;
  png.reserve(std::size_t(image.width) * image.height);
  write_png("(in memory)", image.width, image.height, 8, PNG_COLOR_TYPE_RGB, image.width * 3,
            reinterpret_cast<const std::uint8_t*>(image.pixels.data()), false, &png);
  return png;
}

}  // namespace pipeloc
