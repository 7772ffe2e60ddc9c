// STL files: the input is the whole file.
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  csgvox::fuzz::readAsScanAndMesh(csgvox::fuzz::bytes(data, size), csgvox::ScanFileType::Stl);
  return 0;
}
