// The window solve's inner loops for CPUs with AVX2: this file is compiled
// with -mavx2 (core/CMakeLists.txt) and called only where the CPU has it
// (poisson_kernels.cpp).
#define GDVR_POISSON_KERNELS kPoissonKernelsAvx2
#define GDVR_POISSON_KERNELS_ISA "avx2"
#include "core/recon/poisson_kernels.inl"
