#pragma once
/// The min/max fitness kernel over one chunk of points, compiled once per
/// instruction-set level (portable, AVX2, AVX-512; core/cpu_features.h) and
/// chosen at run time. Plain data only: the files compiled with wider
/// instruction sets must not instantiate library templates (see
/// core/cpu_features.h). Every level gives the same sums bit for bit: the
/// kernel only selects and negates floats, and sums in a fixed order.

#include <cstddef>
#include <cstdint>

namespace csgvox::fitness_detail {

/// Points per chunk: the value stack of a program stays in L1.
inline constexpr std::size_t kChunk = 256;

/// Postfix instructions. Leaf pushes a primitive's field, LeafNeg its
/// negation; Negate negates the top; Min and Max pop two and push one;
/// MinLeaf, MaxLeaf (and their Neg forms) combine the top with a primitive's
/// (negated) field in place — a Leaf followed by Min or Max, fused.
enum class Op : std::uint8_t {
  Leaf,
  LeafNeg,
  Negate,
  Min,
  Max,
  MinLeaf,
  MinLeafNeg,
  MaxLeaf,
  MaxLeafNeg
};

/// One instruction.
struct Instr {
  Op op;
  std::uint16_t leaf;  ///< the Leaf forms: index into the library
};

/// One chunk's work: a program (with fused instructions) and its stacks of
/// stackDepth × kChunk entries.
struct MinMaxChunk {
  const Instr* code = nullptr;
  std::size_t codeSize = 0;
  const float* values = nullptr;        ///< [p][n]
  const float* distanceTerm = nullptr;  ///< [p][n]
  const float* normalTerm = nullptr;    ///< [2p][n]
  std::size_t n = 0;
  float* stackValues = nullptr;
  std::int32_t* stackIds = nullptr;
};

/// Adds the chunk [start, start + m) (m <= kChunk) of Σ exp(−di²) and
/// Σ exp(−θi²) to sums[0] and sums[1].
using MinMaxChunkKernel = void (*)(const MinMaxChunk& k, std::size_t start, std::size_t m,
                                   double* sums);

/// The kernel of each level, one per ISA file (core/cpu_features.h): the
/// vector ones are null where the build gives no flags for their level (not
/// x86-64, or not GCC or Clang). Calling a vector kernel needs a CPU with
/// its level; taking it does not.
MinMaxChunkKernel portableMinMaxChunk();
MinMaxChunkKernel avx2MinMaxChunk();
MinMaxChunkKernel avx512MinMaxChunk();

}  // namespace csgvox::fitness_detail
