#include "core/recon/pcg.h"

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
        float a = 0, b = 0;  // per-chunk float sums, chunks summed in double
        body(r.begin(), r.end(), &a, &b);
        return Pair{acc.first + a, acc.second + b};
      },
      [](Pair a, Pair b) { return Pair{a.first + b.first, a.second + b.second}; });
}

}  // namespace

PcgResult solve_pcg(const PoissonSystem& A, const Field& b, const Field& inv_diag, Field* x_out, int max_iterations,
                    double tolerance) {
  const size_t n = b.size();
  float* x = x_out->data();
  const float* B = b.data();
  const float* M = inv_diag.data();
  Field r_f(n), p_f(n), q_f(n);
  float* r = r_f.data();
  float* p = p_f.data();
  float* q = q_f.data();

  // ---- r = b − A x, p = M r ----
  A.apply(x, q);
  const Pair init = reduce_pair(n, [&](size_t i0, size_t i1, float* rz, float* bb) {
    for (size_t i = i0; i < i1; ++i) {
      r[i] = B[i] - q[i];
      p[i] = M[i] * r[i];
      *rz += r[i] * p[i];
      *bb += B[i] * B[i];
    }
  });
  double rz = init.first;
  // A zero right-hand side has the solution 0; measure against 1 then.
  const double b_norm2 = init.second > 0 ? init.second : 1.0;
  const Pair rr0 = reduce_pair(n, [&](size_t i0, size_t i1, float* rr, float*) {
    for (size_t i = i0; i < i1; ++i) *rr += r[i] * r[i];
  });
  double rr = rr0.first;
  const double tol2 = tolerance * tolerance * b_norm2;

  PcgResult res;
  while (res.iterations < max_iterations && rr > tol2) {
    const double pq = A.apply(p, q);
    // pq ≤ 0 only from round-off once converged (A is SPD): stop, don't divide.
    if (!(pq > 0) || !std::isfinite(pq)) break;
    const float step = float(rz / pq);
    const Pair upd = reduce_pair(n, [&](size_t i0, size_t i1, float* rr_acc, float* rz_acc) {
      for (size_t i = i0; i < i1; ++i) {
        x[i] += step * p[i];
        r[i] -= step * q[i];
        *rr_acc += r[i] * r[i];
        *rz_acc += r[i] * r[i] * M[i];
      }
    });
    ++res.iterations;
    rr = upd.first;
    const double rz_new = upd.second;
    if (!(rz > 0)) break;
    const float beta = float(rz_new / rz);
    rz = rz_new;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kChunk), [&](const tbb::blocked_range<size_t>& rg) {
      for (size_t i = rg.begin(); i != rg.end(); ++i) p[i] = M[i] * r[i] + beta * p[i];
    });
  }
  res.relative_residual = std::sqrt(rr / b_norm2);
  res.converged = rr <= tol2;
  return res;
}

}  // namespace gdvr
