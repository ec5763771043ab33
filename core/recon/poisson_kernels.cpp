// Picks the window solve's kernels for this CPU (poisson_kernels.h).
#include "core/recon/poisson_kernels.h"

#include <cstdlib>
#include <cstring>

namespace gdvr {

extern const PoissonKernels kPoissonKernelsBaseline;
#if defined(GDVR_AVX2_KERNELS)
extern const PoissonKernels kPoissonKernelsAvx2;
extern const PoissonKernels kPoissonKernelsAvx512;
#endif

std::vector<const PoissonKernels*> poisson_kernel_variants() {
  std::vector<const PoissonKernels*> v{&kPoissonKernelsBaseline};
#if defined(GDVR_AVX2_KERNELS)
  if (__builtin_cpu_supports("avx2")) v.push_back(&kPoissonKernelsAvx2);
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512dq"))
    v.push_back(&kPoissonKernelsAvx512);
#endif
  return v;
}

const PoissonKernels& poisson_kernels() {
  static const PoissonKernels* chosen = [] {
    const auto variants = poisson_kernel_variants();
    // GDVR_POISSON_KERNELS names a variant to run instead of the fastest (for
    // benchmarks; all variants give the same bits). One the CPU lacks is ignored.
    if (const char* want = std::getenv("GDVR_POISSON_KERNELS"))
      for (const PoissonKernels* k : variants)
        if (std::strcmp(k->isa, want) == 0) return k;
    return variants.back();
  }();
  return *chosen;
}

}  // namespace gdvr
