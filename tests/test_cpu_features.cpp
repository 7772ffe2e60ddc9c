#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <string>

#include "core/cpu_features.h"

namespace csgvox {
namespace {

TEST(CpuFeatures, NamesRoundTrip) {
  for (SimdLevel level : {SimdLevel::Portable, SimdLevel::Avx2, SimdLevel::Avx512}) {
    EXPECT_EQ(parseSimdLevel(simdLevelName(level)), level);
  }
  EXPECT_EQ(simdLevelName(SimdLevel::Avx512), "avx512");
  EXPECT_EQ(parseSimdLevel("AVX2"), SimdLevel::Avx2);
  EXPECT_EQ(parseSimdLevel("sse4"), std::nullopt);
  EXPECT_EQ(parseSimdLevel(""), std::nullopt);
  EXPECT_EQ(parseSimdLevel("avx5120"), std::nullopt);
}

TEST(CpuFeatures, SupportedLevelsRunFromPortableToTheDetectedOne) {
  const auto levels = supportedSimdLevels();
  ASSERT_FALSE(levels.empty());
  EXPECT_EQ(levels.front(), SimdLevel::Portable);
  EXPECT_EQ(levels.back(), detectedSimdLevel());
  EXPECT_TRUE(std::is_sorted(levels.begin(), levels.end()));
  EXPECT_EQ(levels.size(), std::size_t(detectedSimdLevel()) + 1);
}

TEST(CpuFeatures, DetectionAgreesWithTheCpuFlags) {
#if defined(__x86_64__) && defined(__GNUC__)
  __builtin_cpu_init();
  const bool avx512 = __builtin_cpu_supports("avx512f") &&
                      __builtin_cpu_supports("avx512vpopcntdq") &&
                      __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512vl");
  EXPECT_EQ(detectedSimdLevel() >= SimdLevel::Avx2, bool(__builtin_cpu_supports("avx2")));
  EXPECT_EQ(detectedSimdLevel() == SimdLevel::Avx512, avx512);
#else
  EXPECT_EQ(detectedSimdLevel(), SimdLevel::Portable);
#endif
}

TEST(CpuFeatures, SetLevelIsCappedAndScopedLevelRestores) {
  const SimdLevel before = simdLevel();
  EXPECT_LE(before, detectedSimdLevel());
  {
    const ScopedSimdLevel portable(SimdLevel::Portable);
    EXPECT_EQ(portable.level(), SimdLevel::Portable);
    EXPECT_EQ(simdLevel(), SimdLevel::Portable);
    {
      // The highest level, and a value above every level, are capped.
      const ScopedSimdLevel top(SimdLevel::Avx512);
      EXPECT_EQ(top.level(), detectedSimdLevel());
      EXPECT_EQ(simdLevel(), detectedSimdLevel());
      EXPECT_EQ(setSimdLevel(SimdLevel(9)), detectedSimdLevel());
    }
    EXPECT_EQ(simdLevel(), SimdLevel::Portable);
  }
  EXPECT_EQ(simdLevel(), before);
  EXPECT_EQ(resetSimdLevel(), before);  // nothing had set a level before this test
}

// CSGVOX_SIMD is read once per process, so each case runs in a fresh child
// (a re-executed test binary) that exits with the level it uses.
class SimdEnvironment : public testing::Test {
 protected:
  void SetUp() override { GTEST_FLAG_SET(death_test_style, "threadsafe"); }
  void TearDown() override { unsetenv("CSGVOX_SIMD"); }

  static void expectLevelUnder(const char* value, SimdLevel expected, const char* stderrPattern) {
    setenv("CSGVOX_SIMD", value, 1);
    EXPECT_EXIT(std::exit(int(simdLevel())), testing::ExitedWithCode(int(expected)), stderrPattern);
  }
};

TEST_F(SimdEnvironment, PortableIsHonoured) {
  expectLevelUnder("portable", SimdLevel::Portable, "^$");
}

TEST_F(SimdEnvironment, Avx2IsHonouredOrCapped) {
  expectLevelUnder("avx2", std::min(SimdLevel::Avx2, detectedSimdLevel()), "^$");
}

TEST_F(SimdEnvironment, Avx512IsCappedToTheCpu) {
  expectLevelUnder("AVX512", detectedSimdLevel(), "^$");
}

TEST_F(SimdEnvironment, AnUnknownNameIsReportedAndIgnored) {
  expectLevelUnder("sse9", detectedSimdLevel(), "CSGVOX_SIMD=sse9 names no level");
}

TEST_F(SimdEnvironment, SetLevelOverridesTheEnvironment) {
  setenv("CSGVOX_SIMD", "portable", 1);
  EXPECT_EXIT(
      {
        const SimdLevel fromEnvironment = simdLevel();
        const SimdLevel set = setSimdLevel(SimdLevel::Avx512);
        const SimdLevel reset = resetSimdLevel();
        std::exit(fromEnvironment == SimdLevel::Portable && set == detectedSimdLevel() &&
                          reset == SimdLevel::Portable
                      ? 0
                      : 1);
      },
      testing::ExitedWithCode(0), "^$");
}

}  // namespace
}  // namespace csgvox
