// tree.json: the input is the whole file. A tree that reads must also write
// and read back.
#include <cstdlib>
#include <optional>

#include "fuzz/fuzz_input.h"
#include "io/tree_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::optional<csgvox::CsgTree> tree;
  try {
    std::istringstream in(csgvox::fuzz::bytes(data, size));
    tree = csgvox::readTreeJson(in, "fuzz-input");
  } catch (const csgvox::ParseError&) {
    return 0;
  } catch (const csgvox::IoError&) {
    return 0;
  }
  std::stringstream text;
  csgvox::writeTreeJson(text, *tree);
  csgvox::readTreeJson(text,
                       "written-back");  // throws (and aborts the run) if it does not read back
  return 0;
}
