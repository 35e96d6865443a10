#include "image.hpp"

#include <png.h>

#include <corrlap/core/error.hpp>
#include <limits>

namespace corrlap {

Image::Image(int w, int h, std::uint8_t r, std::uint8_t g, std::uint8_t b) : width(w), height(h) {
  if (w <= 0 || h <= 0) throw InputError("image: size " + std::to_string(w) + " x " + std::to_string(h));
  rgb.resize(std::size_t(w) * std::size_t(h) * 3);
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = r;
    rgb[i + 1] = g;
    rgb[i + 2] = b;
  }
}

// libpng's simplified API (1.6): no setjmp, errors come back in image.message.
void write_png(const std::string& path, const Image& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != std::size_t(image.width) * std::size_t(image.height) * 3)
    throw InputError("write_png: " + path + ": the image has no pixels or the wrong number of bytes");
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = png_uint_32(image.width);
  png.height = png_uint_32(image.height);
  png.format = PNG_FORMAT_RGB;
  if (!png_image_write_to_file(&png, path.c_str(), 0, image.rgb.data(), 0, nullptr))
    throw IoError(path + ": cannot write the PNG (" + png.message + ")");
}

Image read_png(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str()))
    throw IoError(path + ": cannot read as PNG (" + png.message + ")");
  if (png.width > 1u << 15 || png.height > 1u << 15) {
    png_image_free(&png);
    throw IoError(path + ": PNG of " + std::to_string(png.width) + " x " + std::to_string(png.height) +
                  " pixels is larger than 32768 x 32768");
  }
  png.format = PNG_FORMAT_RGB;
  Image image(int(png.width), int(png.height));
  png_color white{255, 255, 255};
  if (!png_image_finish_read(&png, &white, image.rgb.data(), 0, nullptr))
    throw IoError(path + ": corrupt PNG (" + png.message + ")");
  return image;
}

}  // namespace corrlap
