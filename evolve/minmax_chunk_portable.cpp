// The min/max chunk kernel for every x86-64 (evolve/minmax_chunk.h).
#include "evolve/minmax_chunk.h"

#define CSGVOX_MINMAX_CHUNK minMaxChunkPortable
#include "evolve/minmax_chunk.inc"
