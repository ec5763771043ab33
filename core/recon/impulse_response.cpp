#include "core/recon/impulse_response.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <memory>

#include "core/recon/reconstruct.h"

namespace gdvr {

Expected<std::vector<double>> impulse_response_by_distance(const ReconSettings& settings, int size, int frames) {
  if (size < 3 || frames < 1)
    return invalid_argument("impulse response: needs a window of at least 3x3 pixels and one frame, got " +
                            std::to_string(size) + "x" + std::to_string(size) + "x" + std::to_string(frames));
  GradientWindow w;
  for (int t = 0; t < frames; ++t) {
    auto f = std::make_shared<GradientFrame>();
    for (Term term : kAllTerms) f->buffer(term) = Image(size, size, 1);
    if (t == frames / 2) f->buffer(Term::kPrimal).at(size / 2, size / 2, 0) = 1.0f;
    w.frames.push_back(std::move(f));
  }
  ReconSettings s = settings;
  s.method = ReconMethod::kL2;
  // Far below the response's tail, so that CG's own error does not hide it.
  s.l2_tolerance = 1e-10;
  s.l2_max_iterations = 20000;
  auto r = reconstruct(w, s);
  if (!r.ok()) return r.status();
  std::vector<double> by_distance(size_t(size / 2 + 1), 0.0);
  for (const Image& img : r->frames)
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const int d = std::max(std::abs(x - size / 2), std::abs(y - size / 2));
        if (size_t(d) < by_distance.size())
          by_distance[size_t(d)] = std::max(by_distance[size_t(d)], double(std::fabs(img.at(x, y, 0))));
      }
  const double peak = *std::max_element(by_distance.begin(), by_distance.end());
  if (peak > 0)
    for (double& v : by_distance) v /= peak;
  return by_distance;
}

}  // namespace gdvr
