// The min/max chunk kernel for every x86-64 (evolve/minmax_chunk.h).
#include "evolve/minmax_chunk.h"
#include "evolve/minmax_chunk.inc"

csgvox::fitness_detail::MinMaxChunkKernel csgvox::fitness_detail::portableMinMaxChunk() {
  return &minMaxChunk;
}
