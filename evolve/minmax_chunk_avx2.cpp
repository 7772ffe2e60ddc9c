// The min/max chunk kernel compiled with the AVX2 flags
// (cmake/csgvox_simd.cmake; evolve/minmax_chunk.h); its export is null where
// the build gives no such flags.
#include "evolve/minmax_chunk.h"

#if defined(__AVX2__)

#include "evolve/minmax_chunk.inc"

csgvox::fitness_detail::MinMaxChunkKernel csgvox::fitness_detail::avx2MinMaxChunk() {
  return &minMaxChunk;
}

#else

csgvox::fitness_detail::MinMaxChunkKernel csgvox::fitness_detail::avx2MinMaxChunk() {
  return nullptr;
}

#endif
