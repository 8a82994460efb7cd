// ENDOTOWER_WIDE_VECTORS: on an x86-64 host, a function so marked is compiled twice,
// for the baseline (SSE2) and for AVX2, and the loader picks the one the CPU runs
// (GCC's target_clones, an ifunc). For the per-frame loops over whole images (the
// 1080p reduction, the mask operations) whose vectorised bodies do 32 bytes a step
// instead of 16. Integer code, or float divisions alone (correctly rounded in either
// version: ToolLikelihood::cells): the results are the same bytes either way (AVX2
// alone brings no FMA, so no floating-point contraction changes). The board (aarch64)
// has NEON as its baseline and builds one version; so do clang (clang-tidy, the
// fuzzers) and the sanitizer builds, which thereby test the baseline loops. Private
// to app/vision.
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define ENDOTOWER_WIDE_VECTORS __attribute__((target_clones("avx2", "default")))
#else
#define ENDOTOWER_WIDE_VECTORS
#endif
