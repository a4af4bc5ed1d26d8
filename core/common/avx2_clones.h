// MODESTACK_AVX2_CLONES before a function with hot vectorised loops compiles it
// twice, for AVX2 and for the x86-64 baseline, and the program picks the copy when
// it loads (function multiversioning, an ifunc): 4 doubles or 8 floats a step
// where the CPU has them, without building for one CPU. "avx2" enables no FMA, so
// both copies make the same IEEE operations in the same order and give the same
// bits: runs on different machines of a farm agree.
// Not under ThreadSanitizer: the clones' ifunc resolver runs while the program is
// being relocated, before TSan's runtime is up, and crashes there. Not in fuzzing
// builds: clang 14 with afl++'s coverage pass crashes compiling them.
#pragma once

#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define MODESTACK_THREAD_SANITIZER 1
#endif
#endif
#if defined(__SANITIZE_THREAD__)
#define MODESTACK_THREAD_SANITIZER 1
#endif

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(MODESTACK_THREAD_SANITIZER) && \
    !defined(FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION) && !defined(__AFL_COMPILER)
#define MODESTACK_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define MODESTACK_AVX2_CLONES
#endif
