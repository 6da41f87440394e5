// vector_clones.h — MANIPID_VECTOR_CLONES: a kernel compiled for baseline x86-64 and for AVX2.
#pragma once

#include <cstddef>  // defines __GLIBC__ (through features.h), tested below

// The build targets generic x86-64 (SSE2). On x86-64 with GCC/Clang the kernels marked with
// this are also compiled for AVX2 and picked at load time (function multiversioning, a GNU
// ifunc): twice the vector width, and AVX's three-operand instructions drop the register
// copies SSE2 needs around every product, for the same binary. "avx2" does not enable FMA, so
// no product is fused and both versions give the same numbers bit for bit. Define
// MANIPID_NO_FUNCTION_CLONES to build the generic version only. The kernels are kept out of
// line either way: inlined into their callers they lose registers to spills.
// ThreadSanitizer crashes in the clones' load-time resolvers, so TSan builds go generic.
#if defined(__SANITIZE_THREAD__) && !defined(MANIPID_NO_FUNCTION_CLONES)
#define MANIPID_NO_FUNCTION_CLONES
#endif
#if defined(__x86_64__) && defined(__GNUC__) && defined(__GLIBC__) && !defined(MANIPID_NO_FUNCTION_CLONES)
#define MANIPID_VECTOR_CLONES __attribute__((target_clones("avx2", "default"), noinline))
#elif defined(__GNUC__)
#define MANIPID_VECTOR_CLONES __attribute__((noinline))
#else
#define MANIPID_VECTOR_CLONES
#endif

namespace manipid::detail {

/// Σ x[i]·y[i] in four interleaved partial sums, which the compiler vectorises inside a kernel
/// marked MANIPID_VECTOR_CLONES (one running sum would be a chain it may not reorder). The same
/// order of operations in every clone, so the same result bit for bit.
[[gnu::always_inline]] inline double dot(const double* x, const double* y, std::ptrdiff_t m) {
  double lanes[4] = {0.0, 0.0, 0.0, 0.0};
  std::ptrdiff_t i = 0;
  for (; i + 4 <= m; i += 4) {
    for (int lane = 0; lane < 4; ++lane) lanes[lane] += x[i + lane] * y[i + lane];
  }
  for (; i < m; ++i) lanes[0] += x[i] * y[i];
  return (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]);
}

}  // namespace manipid::detail
