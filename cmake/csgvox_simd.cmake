# Compile options of the instruction-set levels of core/cpu_features.h.
#
#   csgvox_simd_sources(AVX2 a_avx2.cpp ...)
#   csgvox_simd_sources(AVX512 a_avx512.cpp ...)
#
# compiles the named sources (of a target in the calling directory) for that
# level. Only these files get the flags: the rest of the build stays portable,
# and the kernels in these files run only after the run-time check of
# simdLevel(). On other processors or compilers the files get no flags; their
# `#if defined(__AVX2__)` / `#if defined(__AVX512F__)` guards then leave them
# empty and the portable kernels are used.
include_guard(GLOBAL)

function(csgvox_simd_sources level)
  if(NOT CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64|i.86"
     OR NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    return()
  endif()
  # The options live in the function, not in variables of the file: the
  # include guard skips the file in every directory but the first, and a
  # variable set there would be empty in the others.
  # -ffp-contract=off: with FMA available GCC would otherwise fuse a * b + c on
  # its own, and floating-point kernels would round differently per level.
  set(avx2 -mavx2 -mfma -mbmi -mbmi2 -mpopcnt -ffp-contract=off)
  if(level STREQUAL "AVX2")
    set(options ${avx2})
  elseif(level STREQUAL "AVX512")
    set(options ${avx2} -mavx512f -mavx512bw -mavx512dq -mavx512vl -mavx512cd -mavx512vpopcntdq)
  else()
    message(FATAL_ERROR "csgvox_simd_sources: unknown level '${level}' (AVX2 or AVX512)")
  endif()
  set_source_files_properties(${ARGN} DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}
                              PROPERTIES COMPILE_OPTIONS "${options}")
endfunction()
