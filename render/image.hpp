#pragma once
// An 8-bit RGB raster and its PNG file (libpng). Pixels row by row from the top, 3 bytes each.
#include <cstdint>
#include <string>
#include <vector>

namespace corrlap {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3 bytes, row-major from the top-left pixel

  Image() = default;
  /// A width x height image filled with one colour.
  Image(int width, int height, std::uint8_t r = 255, std::uint8_t g = 255, std::uint8_t b = 255);
  std::uint8_t* pixel(int x, int y) { return rgb.data() + 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x)); }
  const std::uint8_t* pixel(int x, int y) const {
    return rgb.data() + 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
  }
};

/// Writes an 8-bit RGB PNG. Throws IoError naming the file when it cannot be written.
void write_png(const std::string& path, const Image& image);
/// Reads any PNG as 8-bit RGB (alpha composited on white). Throws IoError naming the file.
Image read_png(const std::string& path);

}  // namespace corrlap
