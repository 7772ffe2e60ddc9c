#include "core/cpu_features.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace csgvox {
namespace {

#if (defined(__x86_64__) || defined(__i386__)) && (defined(__GNUC__) || defined(__clang__))
#define CSGVOX_X86_DETECTION 1
#endif

SimdLevel detect() {
#ifdef CSGVOX_X86_DETECTION
  // The feature bits of libgcc/compiler-rt include the check that the OS
  // saves the AVX and AVX-512 registers (XGETBV).
  __builtin_cpu_init();
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                    __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2") &&
                    __builtin_cpu_supports("popcnt");
  if (!avx2) return SimdLevel::Portable;
  const bool avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
                      __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512vl") &&
                      __builtin_cpu_supports("avx512cd") &&
                      __builtin_cpu_supports("avx512vpopcntdq");
  return avx512 ? SimdLevel::Avx512 : SimdLevel::Avx2;
#else
  return SimdLevel::Portable;
#endif
}

SimdLevel capped(SimdLevel requested) { return std::min(requested, detectedSimdLevel()); }

// The default level: CSGVOX_SIMD, else the detected one. Read once.
SimdLevel defaultSimdLevel() {
  static const SimdLevel level = [] {
    const char* text = std::getenv("CSGVOX_SIMD");
    if (text == nullptr || *text == '\0') return detectedSimdLevel();
    if (const auto named = parseSimdLevel(text)) return capped(*named);
    std::fprintf(stderr,
                 "csgvox: CSGVOX_SIMD=%s names no level (portable, avx2, avx512); using %s\n", text,
                 std::string(simdLevelName(detectedSimdLevel())).c_str());
    return detectedSimdLevel();
  }();
  return level;
}

// The level in use; -1 until the first simdLevel() or setSimdLevel().
constinit std::atomic<int> current{-1};

}  // namespace

SimdLevel detectedSimdLevel() {
  static const SimdLevel level = detect();
  return level;
}

SimdLevel simdLevel() {
  int level = current.load(std::memory_order_relaxed);
  if (level < 0) [[unlikely]] {
    int unset = -1;
    current.compare_exchange_strong(unset, int(defaultSimdLevel()), std::memory_order_relaxed);
    level = current.load(std::memory_order_relaxed);
  }
  return SimdLevel(level);
}

SimdLevel setSimdLevel(SimdLevel requested) {
  const SimdLevel level = capped(requested);
  current.store(int(level), std::memory_order_relaxed);
  return level;
}

SimdLevel resetSimdLevel() { return setSimdLevel(defaultSimdLevel()); }

std::string_view simdLevelName(SimdLevel level) {
  switch (level) {
    case SimdLevel::Portable:
      return "portable";
    case SimdLevel::Avx2:
      return "avx2";
    case SimdLevel::Avx512:
      return "avx512";
  }
  return "unknown";
}

std::optional<SimdLevel> parseSimdLevel(std::string_view text) {
  std::string lower(text);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  for (SimdLevel level : {SimdLevel::Portable, SimdLevel::Avx2, SimdLevel::Avx512}) {
    if (lower == simdLevelName(level)) return level;
  }
  return std::nullopt;
}

std::vector<SimdLevel> supportedSimdLevels() {
  std::vector<SimdLevel> levels;
  for (int l = 0; l <= int(detectedSimdLevel()); ++l) levels.push_back(SimdLevel(l));
  return levels;
}

}  // namespace csgvox
