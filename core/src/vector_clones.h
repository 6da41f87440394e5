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
