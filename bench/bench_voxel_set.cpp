// Throughput of the bitset operations behind the voxel optimisation, next to
// the machine's memory copy bandwidth. Run: build/bench/bench_voxel_set

#include <benchmark/benchmark.h>

#include <cstring>
#include <random>

#include "voxel/voxel_set.h"

namespace {

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

// |a ∩ b| without materialising the intersection: the phase-1/phase-2 inner loop.
void AndPopcount(benchmark::State& state) {
  const std::size_t bits = cube(state.range(0));
  const VoxelSet a = randomSet(bits, 1), b = randomSet(bits, 2);
  for (auto _ : state) benchmark::DoNotOptimize(VoxelSet::countAnd(a, b));
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(2 * bits / 8));
}

// a &= b in place, then |a|.
void AndInPlaceThenCount(benchmark::State& state) {
  const std::size_t bits = cube(state.range(0));
  VoxelSet a = randomSet(bits, 1);
  const VoxelSet b = randomSet(bits, 2);
  for (auto _ : state) {
    a |= b;  // keep a from going empty over iterations
    a &= b;
    benchmark::DoNotOptimize(a.count());
  }
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(4 * bits / 8));
}

void AndNotPopcount(benchmark::State& state) {
  const std::size_t bits = cube(state.range(0));
  const VoxelSet a = randomSet(bits, 1), b = randomSet(bits, 2);
  for (auto _ : state) benchmark::DoNotOptimize(VoxelSet::countAndNot(a, b));
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(2 * bits / 8));
}

// Reference: memcpy of one set's bytes (read + write).
void Memcpy(benchmark::State& state) {
  const std::size_t bytes = cube(state.range(0)) / 8;
  std::vector<char> src(bytes, 1), dst(bytes);
  for (auto _ : state) {
    std::memcpy(dst.data(), src.data(), bytes);
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(std::int64_t(state.iterations()) * std::int64_t(2 * bytes));
}

BENCHMARK(AndPopcount)->Arg(64)->Arg(128)->Arg(256);
BENCHMARK(AndNotPopcount)->Arg(64)->Arg(128)->Arg(256);
BENCHMARK(AndInPlaceThenCount)->Arg(64)->Arg(128)->Arg(256);
BENCHMARK(Memcpy)->Arg(64)->Arg(128)->Arg(256);

}  // namespace

BENCHMARK_MAIN();
