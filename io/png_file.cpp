#include "io/png_file.h"

#include <fstream>
#include <iterator>
#include <ostream>
#include <stdexcept>
#include <string>

#include "io/errors.h"
#include "io/file_util.h"

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STB_IMAGE_STATIC
#define STBI_ONLY_PNG
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wsign-compare"
#include <stb_image.h>
#include <stb_image_write.h>
#pragma GCC diagnostic pop

namespace csgvox {
namespace {

void appendToStream(void* context, void* data, int size) {
  static_cast<std::ostream*>(context)->write(static_cast<const char*>(data), size);
}

}  // namespace

void writePng(const std::filesystem::path& path, const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * std::size_t(image.width) * std::size_t(image.height)) {
    throw std::invalid_argument(path.string() + ": cannot write an empty or malformed picture");
  }
  writeFileAtomically(
      path,
      [&](std::ostream& out) {
        if (!stbi_write_png_to_func(appendToStream, &out, image.width, image.height, 3,
                                    image.rgb.data(), 3 * image.width)) {
          throw IoError(path.string() + ": cannot encode the PNG");
        }
      },
      true);
}

RgbImage readPng(const std::filesystem::path& path) {
  requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) throw IoError(path.string() + ": cannot be read");
  int w = 0, h = 0, channels = 0;
  stbi_uc* pixels = stbi_load_from_memory(reinterpret_cast<const stbi_uc*>(bytes.data()),
                                          static_cast<int>(bytes.size()), &w, &h, &channels, 3);
  if (!pixels) {
    throw ParseError(path.string() + ": not a readable PNG (" + stbi_failure_reason() + ")");
  }
  RgbImage image{w, h, std::vector<std::uint8_t>(pixels, pixels + 3 * std::size_t(w) * h)};
  stbi_image_free(pixels);
  return image;
}

}  // namespace csgvox
