// The min/max chunk kernel compiled for avx2 (evolve/minmax_chunk.h); without
// the instruction set's flags it is the portable kernel under this name.
#include "evolve/minmax_chunk.h"

#define CSGVOX_MINMAX_CHUNK minMaxChunkAvx2
#include "evolve/minmax_chunk.inc"

namespace csgvox::fitness_detail {

bool minMaxChunkAvx2Built() {
#if defined(__AVX2__)
  return true;
#else
  return false;
#endif
}

}  // namespace csgvox::fitness_detail
