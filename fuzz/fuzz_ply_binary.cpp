// PLY in binary: the first byte picks the byte order (even: little endian,
// odd: big endian); the rest is everything after the "ply" and format lines.
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const char* format = (data[0] & 1) == 0 ? "ply\nformat binary_little_endian 1.0\n"
                                          : "ply\nformat binary_big_endian 1.0\n";
  csgvox::fuzz::readAsScanAndMesh(format + csgvox::fuzz::bytes(data + 1, size - 1),
                                  csgvox::ScanFileType::Ply);
  return 0;
}
