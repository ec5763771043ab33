// The window solve's inner loops for any x86-64 (or other) CPU: the build's
// baseline instruction set (poisson_kernels.inl).
#define GDVR_POISSON_KERNELS kPoissonKernelsBaseline
#define GDVR_POISSON_KERNELS_ISA "baseline"
#include "core/recon/poisson_kernels.inl"
