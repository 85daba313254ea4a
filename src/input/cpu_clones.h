// Internal: loops that GCC 12 vectorises only with AVX2 (a compare narrowed to a byte or a count)
// get an AVX2 clone, chosen at load time, where the compiler and processor family allow; elsewhere
// the plain function. Clones hold compares and no FMA: every clone gives the same answers.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define SDFCONTOUR_AVX2_CLONE __attribute__((target_clones("avx2", "default")))
/// Minima and maxima over finite values vectorise only with fast math (the order of a reduction).
#define SDFCONTOUR_AVX2_CLONE_FAST_MATH \
  __attribute__((target_clones("avx2", "default"), optimize("fast-math")))
#else
#define SDFCONTOUR_AVX2_CLONE
#define SDFCONTOUR_AVX2_CLONE_FAST_MATH
#endif
