#pragma once
/// PNG pictures (stb_image_write and stb_image from libstb-dev).

#include <filesystem>

#include "core/rgb_image.h"

namespace csgvox {

/// Writes `image` as an 8-bit RGB PNG, atomically.
/// @throw std::invalid_argument for an empty picture or one whose pixel
///        count does not match its size; IoError when it cannot be written.
void writePng(const std::filesystem::path& path, const RgbImage& image);

/// Reads a PNG (any colour type, converted to 8-bit RGB).
/// @throw IoError when the file cannot be opened; ParseError when it is not
///        a readable PNG.
RgbImage readPng(const std::filesystem::path& path);

}  // namespace csgvox
