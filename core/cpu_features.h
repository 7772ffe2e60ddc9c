#pragma once
/// The vector instruction-set level the process uses for its hot kernels,
/// detected once at run time, so that one build runs on any x86-64 CPU and
/// still uses AVX2 or AVX-512 where the CPU has them.
///
/// How a kernel uses it (the bitset kernels of voxel/bitset_kernels.h are the
/// worked example):
///  - one implementation per level, the portable one in an ordinary .cpp, the
///    others each in their own .cpp compiled with the level's flags
///    (`csgvox_simd_sources(AVX2 file.cpp)` / `csgvox_simd_sources(AVX512
///    file.cpp)` from cmake/csgvox_simd.cmake);
///  - an ISA-specific file holds only intrinsics and code with internal
///    linkage (anonymous namespace; templates instantiated with a type of the
///    anonymous namespace count, as in voxel/bitset_kernel_loops.h) and
///    exports one function returning a constant table of its kernels. It calls
///    no inline function or template of a library or of another header
///    (std::popcount, std::min, containers), because
///    the linker may keep that file's copy of such a function for the whole
///    program, and then AVX code would run on a CPU without AVX; and it has no
///    dynamic initialisation (`constinit` tables), which would run at start-up
///    before any check. Its body sits under `#if defined(__AVX2__)` (or
///    `__AVX512F__`), and its export returns nullptr when the file was built
///    without the flags (other compilers or processors);
///  - each call picks the implementation of `simdLevel()` (a switch or a table
///    indexed by the level), falling back to the next lower level built.
/// Every implementation of a kernel must give the same results bit for bit,
/// so the level changes speed, never output. For floating-point kernels that
/// means the same operations in the same order in every lane: no FMA unless
/// the portable code uses std::fma too (the level flags include
/// -ffp-contract=off, so the compiler does not fuse a * b + c by itself), and
/// no reordered reductions.
/// Check a new ISA file with `nm -C file.o`: one global symbol, no weak ones.

#include <array>
#include <optional>
#include <string_view>
#include <vector>

namespace csgvox {

/// Instruction-set levels, in increasing order of capability.
enum class SimdLevel : int {
  /// x86-64 as the whole build targets it (or any other processor).
  Portable = 0,
  /// AVX2 with FMA, BMI1, BMI2 and POPCNT (Haswell, Zen and later).
  Avx2 = 1,
  /// Avx2 plus AVX-512 F, BW, DQ, VL, CD and VPOPCNTDQ (Ice Lake, Zen 4 and
  /// later; not Skylake-X, which lacks VPOPCNTDQ and gets Avx2).
  Avx512 = 2,
};

/// The highest level this CPU and operating system support (AVX state
/// enabled by the OS included). Detected on the first call; thread-safe.
SimdLevel detectedSimdLevel();

/// Per level (index: the level), the kernel of the highest level at or
/// below it that both this CPU and the build have: `avx2` and `avx512` are
/// the ISA files' exports, called only where the CPU has their level and
/// returning null where the build has no flags for it. `Kernel` is a
/// pointer (a kernel function or a table of kernels).
template <class Kernel>
std::array<Kernel, 3> kernelsByLevel(Kernel portable, Kernel (*avx2)(), Kernel (*avx512)()) {
  const SimdLevel cpu = detectedSimdLevel();
  const Kernel builtAvx2 = cpu >= SimdLevel::Avx2 ? avx2() : nullptr;
  const Kernel builtAvx512 = cpu >= SimdLevel::Avx512 ? avx512() : nullptr;
  const Kernel upToAvx2 = builtAvx2 ? builtAvx2 : portable;
  return {portable, upToAvx2, builtAvx512 ? builtAvx512 : upToAvx2};
}

/// The level the kernels use now: the one set by setSimdLevel(), else the
/// one named by the environment variable CSGVOX_SIMD (`portable`, `avx2` or
/// `avx512`, read on the first call), else detectedSimdLevel(). Never above
/// detectedSimdLevel(). A CSGVOX_SIMD value that names no level is reported
/// once on stderr and ignored. Thread-safe (an atomic load).
SimdLevel simdLevel();

/// Makes the kernels use `requested`, capped to detectedSimdLevel(), and
/// returns the level now in use. Meant for tests, benchmarks and a user's
/// explicit choice. Thread-safe: calls dispatched after it returns use the
/// new level, calls already running finish on the level they started with
/// (harmless, since every level gives identical results).
SimdLevel setSimdLevel(SimdLevel requested);

/// Returns to the default level (CSGVOX_SIMD, else the detected one) and
/// returns it. Thread-safe like setSimdLevel().
SimdLevel resetSimdLevel();

/// Lower-case name of a level: "portable", "avx2" or "avx512".
std::string_view simdLevelName(SimdLevel level);

/// The level named by `text` (a name of simdLevelName(), any case), or
/// nullopt when it names none.
std::optional<SimdLevel> parseSimdLevel(std::string_view text);

/// The levels this CPU supports, from Portable up to detectedSimdLevel().
std::vector<SimdLevel> supportedSimdLevels();

/// Sets a level for the lifetime of the object and restores the previous
/// one on destruction (tests and benchmarks). Not for use from several
/// threads at once: the level is process-wide.
class ScopedSimdLevel {
 public:
  /// Uses `requested` (capped to the CPU's level) until destruction.
  explicit ScopedSimdLevel(SimdLevel requested)
      : previous_(simdLevel()), level_(setSimdLevel(requested)) {}
  ~ScopedSimdLevel() { setSimdLevel(previous_); }
  ScopedSimdLevel(const ScopedSimdLevel&) = delete;
  ScopedSimdLevel& operator=(const ScopedSimdLevel&) = delete;

  /// The level in use while the object lives (after capping).
  SimdLevel level() const { return level_; }

 private:
  SimdLevel previous_;
  SimdLevel level_;
};

}  // namespace csgvox
