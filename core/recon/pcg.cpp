#include "core/recon/pcg.h"

#include "core/recon/poisson_kernels.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <utility>

namespace gdvr {

namespace {

constexpr size_t kChunk = 16384;

using Pair = std::pair<double, double>;

template <typename Body>
Pair reduce_pair(size_t n, Body body) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<size_t>(0, n, kChunk), Pair{0.0, 0.0},
      [&](const tbb::blocked_range<size_t>& r, Pair acc) {
        // Per-chunk float sums (kept in registers: the body returns them by
        // value so the compiler can vectorise), chunks summed in double.
        const std::pair<float, float> part = body(r.begin(), r.end());
        return Pair{acc.first + part.first, acc.second + part.second};
      },
      [](Pair a, Pair b) { return Pair{a.first + b.first, a.second + b.second}; });
}

}  // namespace

PcgResult solve_pcg(const PoissonSystem& A, const Field& b, const Field& inv_diag, Field* x_out, int max_iterations,
                    double tolerance, PcgWorkspace* workspace) {
  const size_t n = b.size();
  float* x = x_out->data();
  const float* B = b.data();
  const float* M = inv_diag.data();
  PcgWorkspace local;
  PcgWorkspace& ws = workspace ? *workspace : local;
  // Every element is written before it is read (apply writes all of q).
  ws.r.resize(n);
  ws.p.resize(n);
  ws.q.resize(n);
  float* r = ws.r.data();
  float* p = ws.p.data();
  float* q = ws.q.data();

  // ---- r = b − A x, p = M r ----
  A.apply(x, q);
  const Pair init = reduce_pair(n, [&](size_t i0, size_t i1) {
    float rz = 0, bb = 0;
    for (size_t i = i0; i < i1; ++i) {
      r[i] = B[i] - q[i];
      p[i] = M[i] * r[i];
      rz += r[i] * p[i];
      bb += B[i] * B[i];
    }
    return std::pair<float, float>{rz, bb};
  });
  double rz = init.first;
  // A zero right-hand side has the solution 0; measure against 1 then.
  const double b_norm2 = init.second > 0 ? init.second : 1.0;
  const Pair rr0 = reduce_pair(n, [&](size_t i0, size_t i1) {
    float rr = 0;
    for (size_t i = i0; i < i1; ++i) rr += r[i] * r[i];
    return std::pair<float, float>{rr, 0.0f};
  });
  double rr = rr0.first;
  const double tol2 = tolerance * tolerance * b_norm2;

  const PoissonKernels& kernels = poisson_kernels();
  PcgResult res;
  while (res.iterations < max_iterations && rr > tol2) {
    const double pq = A.apply(p, q);
    // pq ≤ 0 only from round-off once converged (A is SPD): stop, don't divide.
    if (!(pq > 0) || !std::isfinite(pq)) break;
    const float step = float(rz / pq);
    // ---- r −= step q, with r·r and r·M·r ----
    // x += step p is deferred to the p pass below, which reads p anyway.
    const Pair upd = reduce_pair(n, [&](size_t i0, size_t i1) {
      const PcgSums sums = kernels.update_residual(r, q, M, step, i0, i1);
      return std::pair<float, float>{sums.first, sums.second};
    });
    ++res.iterations;
    rr = upd.first;
    const double rz_new = upd.second;
    // ---- x += step p, then (unless this was the last step) p = M r + β p ----
    const bool last = !(rz > 0) || res.iterations >= max_iterations || rr <= tol2;
    const float beta = last ? 0.0f : float(rz_new / rz);
    rz = rz_new;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kChunk), [&](const tbb::blocked_range<size_t>& rg) {
      kernels.update_solution(x, p, r, M, step, beta, last, rg.begin(), rg.end());
    });
    if (last) break;
  }
  res.relative_residual = std::sqrt(rr / b_norm2);
  res.converged = rr <= tol2;
  return res;
}

}  // namespace gdvr
