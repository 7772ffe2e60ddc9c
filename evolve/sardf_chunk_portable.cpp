// The SARDF chunk kernel for every x86-64 (evolve/sardf_chunk.h).
#include "evolve/sardf_chunk.h"
#include "evolve/sardf_chunk.inc"

csgvox::fitness_detail::SardfChunkKernel csgvox::fitness_detail::portableSardfChunk() {
  return &sardfChunk;
}
