#pragma once
/// \file row_kernel.h
/// NF_ROW_KERNEL: how the row kernels are compiled.

// The row kernels (lib/normals/kernels, one per source file) are plain C++ that the compiler vectorises. On x86-64 each is also built
// for AVX2 and the widest the CPU has is picked at load time (GCC function multiversioning; Clang 14
// clones no templates and no noinline function, so a Clang build, like the sanitizer and fuzz
// builds, keeps the baseline). AVX2 without FMA (no contraction) does the same IEEE operations on
// wider vectors, so the results are the same, bit for bit, on every machine.
// NORMALFLOW_NO_TARGET_CLONES builds the baseline only.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && !defined(NORMALFLOW_NO_TARGET_CLONES)
#define NF_ROW_KERNEL [[gnu::noinline, gnu::target_clones("avx2", "default")]]
#else
#define NF_ROW_KERNEL [[gnu::noinline]]
#endif
// A kernel so marked must be defined in a .cpp of lib/normals/kernels (a template explicitly
// instantiated there) whose compile options include -fno-math-errno and -fno-trapping-math (see
// lib/normals/CMakeLists.txt): the clones and their code are then made once, in that file.
