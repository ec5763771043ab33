#include "core/recon/predicted_improvement.h"

#include <cmath>

namespace gdvr {

double predicted_l2_error_variance(const NoiseLevels& noise, const ReconSettings& s, bool temporal) {
  const double a = s.alpha * s.alpha * s.term_weight(Term::kPrimal);
  const auto d2 = [](double w) { return 4.0 * std::sin(0.5 * w) * std::sin(0.5 * w); };
  // Midpoint rule over [0, 2π)^d; the integrand is smooth and periodic, so a
  // modest grid is already accurate to well under 1 %.
  const int n = temporal ? 64 : 256;
  const int nt = temporal ? n : 1;
  const double h = 2.0 * M_PI / n;
  double sum = 0;
  for (int it = 0; it < nt; ++it) {
    const double dt2 = temporal ? d2((it + 0.5) * h) : 0.0;
    for (int iy = 0; iy < n; ++iy) {
      const double dy2 = d2((iy + 0.5) * h);
      for (int ix = 0; ix < n; ++ix) {
        const double dx2 = d2((ix + 0.5) * h);
        const double D[kTermCount] = {0, dx2, dy2, dt2, dx2 * dt2, dy2 * dt2};
        double num = a * a * noise[Term::kPrimal], den = a;
        for (Term t : {Term::kDx, Term::kDy, Term::kDt, Term::kDxdt, Term::kDydt}) {
          if (is_temporal(t) && !temporal) continue;
          const double w = s.term_weight(t);
          num += w * w * D[term_index(t)] * noise[t];
          den += w * D[term_index(t)];
        }
        sum += num / (den * den);
      }
    }
  }
  return sum / (double(n) * n * nt);
}

Expected<double> predicted_improvement(const NoiseLevels& noise, const ReconSettings& settings, bool temporal) {
  GDVR_RETURN_IF_ERROR(settings.validate());
  if (!(noise[Term::kPrimal] > 0) || !std::isfinite(noise[Term::kPrimal]))
    return invalid_argument("predicted improvement: primal variance must be finite and > 0");
  for (Term t : kAllTerms)
    if (!(noise[t] >= 0) || !std::isfinite(noise[t]))
      return invalid_argument(std::string("predicted improvement: variance of '") + term_name(t) +
                              "' must be finite and >= 0");
  return noise[Term::kPrimal] / predicted_l2_error_variance(noise, settings, temporal);
}

Expected<NoiseLevels> measure_noise_levels(const GradientWindow& window) {
  GDVR_RETURN_IF_ERROR(window.validate());
  NoiseLevels levels;
  for (Term t : kAllTerms) {
    double sum = 0;
    int64_t n = 0;
    for (const auto& f : window.frames)
      for (float v : f->variance(t).data())
        if (std::isfinite(v) && v >= 0) {
          sum += v;
          ++n;
        }
    levels[t] = n > 0 ? sum / n : 0.0;
  }
  if (!(levels[Term::kPrimal] > 0)) return invalid_argument("measure noise levels: the primal has no variance buffer");
  return levels;
}

}  // namespace gdvr
