// The min/max chunk kernel compiled with the AVX-512 flags
// (cmake/csgvox_simd.cmake; evolve/minmax_chunk.h); its export is null where
// the build gives no such flags.
#include "evolve/minmax_chunk.h"

#if defined(__AVX512F__)

#include "evolve/minmax_chunk.inc"

csgvox::fitness_detail::MinMaxChunkKernel csgvox::fitness_detail::avx512MinMaxChunk() {
  return &minMaxChunk;
}

#else

csgvox::fitness_detail::MinMaxChunkKernel csgvox::fitness_detail::avx512MinMaxChunk() {
  return nullptr;
}

#endif
