// The SARDF chunk kernel compiled with the AVX-512 flags
// (cmake/csgvox_simd.cmake; evolve/sardf_chunk.h); its export is null where
// the build gives no such flags.
#include "evolve/sardf_chunk.h"

#if defined(__AVX512F__)

#include "evolve/sardf_chunk.inc"

csgvox::fitness_detail::SardfChunkKernel csgvox::fitness_detail::avx512SardfChunk() {
  return &sardfChunk;
}

#else

csgvox::fitness_detail::SardfChunkKernel csgvox::fitness_detail::avx512SardfChunk() {
  return nullptr;
}

#endif
