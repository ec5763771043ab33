#include "core/util/memory_tuning.h"

#include <cstdlib>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace gdvr {

void retain_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  // GDVR_DEFAULT_MALLOC=1 keeps glibc's defaults (A/B measurements, or a
  // machine short of memory).
  if (const char* v = std::getenv("GDVR_DEFAULT_MALLOC"); v && *v && *v != '0') return;
  mallopt(M_MMAP_MAX, 0);  // large blocks from the heap, not fresh mmap pages
  // Never trim: glibc converts the int to size_t, so -1 is "no limit" (2 GiB,
  // the largest positive int, is less than one 720p window's buffers, and
  // trimming them after each window brought the page faults back).
  mallopt(M_TRIM_THRESHOLD, -1);
  mallopt(M_TOP_PAD, 1 << 30);  // grow the heap in 1 GiB steps (fewer, larger brk calls)
#endif
}

}  // namespace gdvr
