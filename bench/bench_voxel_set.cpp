// Throughput of the bitset operations behind the voxel optimisation on each
// instruction-set level this CPU supports (core/cpu_features.h), next to the
// machine's memory copy bandwidth. Names read operation/level/resolution: a
// set of resolution r has r³ voxels (r = 64: 4096 words, 32 KiB).
// Run: build/bench/bench_voxel_set [--benchmark_filter=...]
//
// Bytes processed: the bytes read and written, so a count over two sets moves
// 2 × r³/8 bytes, an in-place AND 3 × r³/8 (two reads, one write).

#include <benchmark/benchmark.h>

#include <cstring>
#include <random>
#include <string>

#include "core/cpu_features.h"
#include "voxel/voxel_set.h"

namespace {

using csgvox::SimdLevel;
using csgvox::VoxelSet;

VoxelSet randomSet(std::size_t bits, std::uint64_t seed) {
  VoxelSet s(bits);
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution b(0.3);
  for (std::size_t i = 0; i < bits; ++i) {
    if (b(rng)) s.set(i);
  }
  return s;
}

std::size_t cube(std::int64_t res) { return std::size_t(res * res * res); }

// A count over two random sets of resolution range(0), on `level`.
template <std::size_t (*Count)(const VoxelSet&, const VoxelSet&)>
void countPair(benchmark::State& state, SimdLevel level) {
  const csgvox::ScopedSimdLevel scoped(level);
  const std::size_t bits = cube(state.range(0));
  const VoxelSet a = randomSet(bits, 1), b = randomSet(bits, 2);
  for (auto _ : state) benchmark::DoNotOptimize(Count(a, b));
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(2 * bits / 8));
}

// a &= b in place (the set stops changing after the first call; the work
// does not).
void andInPlace(benchmark::State& state, SimdLevel level) {
  const csgvox::ScopedSimdLevel scoped(level);
  const std::size_t bits = cube(state.range(0));
  VoxelSet a = randomSet(bits, 1);
  const VoxelSet b = randomSet(bits, 2);
  for (auto _ : state) {
    a &= b;
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(3 * bits / 8));
}

// |a| of one set.
void countOne(benchmark::State& state, SimdLevel level) {
  const csgvox::ScopedSimdLevel scoped(level);
  const std::size_t bits = cube(state.range(0));
  const VoxelSet a = randomSet(bits, 1);
  for (auto _ : state) benchmark::DoNotOptimize(a.count());
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(bits / 8));
}

// The per-call cost of dispatch: |a ∩ b| of one-word sets.
void countAndOneWord(benchmark::State& state, SimdLevel level) {
  const csgvox::ScopedSimdLevel scoped(level);
  const VoxelSet a = randomSet(64, 1), b = randomSet(64, 2);
  for (auto _ : state) benchmark::DoNotOptimize(VoxelSet::countAnd(a, b));
}

// Reference: memcpy of one set's bytes (read + write).
void memcpySet(benchmark::State& state) {
  const std::size_t bytes = cube(state.range(0)) / 8;
  std::vector<char> src(bytes, 1), dst(bytes);
  for (auto _ : state) {
    std::memcpy(dst.data(), src.data(), bytes);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(2 * bytes));
}

void addSizes(benchmark::internal::Benchmark* b) {
  for (std::int64_t res : {32, 64, 128, 256}) b->Arg(res);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  for (SimdLevel level : csgvox::supportedSimdLevels()) {
    const std::string suffix = "/" + std::string(csgvox::simdLevelName(level));
    addSizes(benchmark::RegisterBenchmark(("CountAnd" + suffix).c_str(),
                                          countPair<VoxelSet::countAnd>, level));
    addSizes(benchmark::RegisterBenchmark(("CountAndNot" + suffix).c_str(),
                                          countPair<VoxelSet::countAndNot>, level));
    addSizes(benchmark::RegisterBenchmark(("CountOr" + suffix).c_str(),
                                          countPair<VoxelSet::countOr>, level));
    addSizes(benchmark::RegisterBenchmark(("Count" + suffix).c_str(), countOne, level));
    addSizes(benchmark::RegisterBenchmark(("AndInPlace" + suffix).c_str(), andInPlace, level));
    benchmark::RegisterBenchmark(("CountAndOneWord" + suffix).c_str(), countAndOneWord, level);
  }
  addSizes(benchmark::RegisterBenchmark("Memcpy", memcpySet));
  benchmark::AddCustomContext("simd_detected",
                              std::string(csgvox::simdLevelName(csgvox::detectedSimdLevel())));
  benchmark::AddCustomContext("simd_default",
                              std::string(csgvox::simdLevelName(csgvox::simdLevel())));
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
