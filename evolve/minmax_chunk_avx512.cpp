// The min/max chunk kernel compiled for avx512 (evolve/minmax_chunk.h); without
// the instruction set's flags it is the portable kernel under this name.
#include "evolve/minmax_chunk.h"

#define CSGVOX_MINMAX_CHUNK minMaxChunkAvx512
#include "evolve/minmax_chunk.inc"

namespace csgvox::fitness_detail {

bool minMaxChunkAvx512Built() {
#if defined(__AVX512F__)
  return true;
#else
  return false;
#endif
}

}  // namespace csgvox::fitness_detail
