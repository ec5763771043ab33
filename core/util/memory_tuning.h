// Allocator tuning for the batch tools (gdvr-render, gdvr-farm, gdvr-report,
// the benchmarks).
//
// A render allocates and frees frame-sized buffers (11 MB per 720p RGB image,
// 74 MB per 20-frame solver vector) again and again. glibc serves blocks that
// large with fresh mmap pages and unmaps them on free, so every reuse pays the
// kernel's zeroing of new pages on first touch: 27 % of all cycles of a 720p
// T-GPT stage-2 run (perf; docs/benchmarks.md). Keeping freed memory in the heap
// (no mmap for large blocks, no trimming) lets the next buffer reuse it:
// stage 2 at 720p, three alternating pairs of runs: median 0.87 s per output
// frame against 0.92 s with glibc's defaults, at the same peak RSS (the runs
// vary by ±8 %, so the gain is small but real in every profile).
// The price is that the process keeps its peak RSS until it exits, which suits
// a batch tool but not the long-running gdvr-server, which does not call this.
#pragma once

namespace gdvr {

// Call once, first thing in main(). No effect where the C library has no
// mallopt (non-glibc).
void retain_freed_memory_for_reuse();

}  // namespace gdvr
