// The SARDF chunk kernel compiled with the AVX2 flags
// (cmake/csgvox_simd.cmake; evolve/sardf_chunk.h); its export is null where
// the build gives no such flags.
#include "evolve/sardf_chunk.h"

#if defined(__AVX2__)

#include "evolve/sardf_chunk.inc"

csgvox::fitness_detail::SardfChunkKernel csgvox::fitness_detail::avx2SardfChunk() {
  return &sardfChunk;
}

#else

csgvox::fitness_detail::SardfChunkKernel csgvox::fitness_detail::avx2SardfChunk() {
  return nullptr;
}

#endif
