// The window solve's inner loops for CPUs with AVX-512 (F, VL, DQ): this file
// is compiled with those flags (core/CMakeLists.txt), and called only where
// the CPU has them (poisson_kernels.cpp). GCC keeps to 256-bit vectors here;
// 512-bit ones (-mprefer-vector-width=512) measured within ±5 % of them on
// the window solve, which is bound by memory traffic (docs/benchmarks.md).
#define GDVR_POISSON_KERNELS kPoissonKernelsAvx512
#define GDVR_POISSON_KERNELS_ISA "avx512"
#include "core/recon/poisson_kernels.inl"
