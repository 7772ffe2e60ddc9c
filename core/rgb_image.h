#pragma once
/// A picture in memory: 8-bit RGB pixels, rows from the top.

#include <array>
#include <cstdint>
#include <vector>

namespace csgvox {

/// An RGB colour, 8 bits per channel.
using Rgb = std::array<std::uint8_t, 3>;

/// A width x height picture; pixel (x, y) (x to the right, y down from the
/// top row) is rgb[3 * (y * width + x) + channel].
struct RgbImage {
  int width = 0;                  ///< pixels per row
  int height = 0;                 ///< rows
  std::vector<std::uint8_t> rgb;  ///< 3 * width * height bytes

  /// A picture filled with one colour.
  static RgbImage filled(int width, int height, Rgb colour) {
    RgbImage image{width, height, {}};
    image.rgb.resize(3 * std::size_t(width) * std::size_t(height));
    for (std::size_t i = 0; i < image.rgb.size(); i += 3) {
      image.rgb[i] = colour[0];
      image.rgb[i + 1] = colour[1];
      image.rgb[i + 2] = colour[2];
    }
    return image;
  }
  /// The colour of pixel (x, y), which must lie in the picture.
  Rgb at(int x, int y) const {
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
  }
  /// Sets pixel (x, y); pixels outside the picture are ignored.
  void set(int x, int y, Rgb c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    const std::size_t i = 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x));
    rgb[i] = c[0];
    rgb[i + 1] = c[1];
    rgb[i + 2] = c[2];
  }
};

}  // namespace csgvox
