// PLY in ASCII: the input is everything after the "ply" and format lines,
// so the fuzzer spends its time on the elements, properties and data.
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  csgvox::fuzz::readAsScanAndMesh("ply\nformat ascii 1.0\n" + csgvox::fuzz::bytes(data, size),
                                  csgvox::ScanFileType::Ply);
  return 0;
}
