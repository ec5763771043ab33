// Synthetic windows with known answers for the reconstruction tests: a smooth
// field plus a moving hard edge, with exact finite-difference gradients
// (the conventions of docs/reconstruction.md), optionally a noisy primal.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "core/recon/gradient_window.h"

namespace gdvr::test {

inline float scene_value(int x, int y, int t, int c) {
  const float smooth = 0.5f + 0.3f * std::sin(0.21f * x + 0.13f * t + c) * std::cos(0.17f * y - 0.05f * t);
  const float edge = (x + 0.5f * y > 20.0f + 2.0f * t) ? 0.6f : 0.0f;
  return (smooth + edge) * (1.0f + 0.2f * c);
}


struct SceneOptions {
  int width = 40, height = 32, frames = 1, channels = 3;
  bool temporal = false;      // fill dt, dxdt, dydt
  float primal_sigma = 0.0f;  // Gaussian noise on the primal
  float gradient_sigma = 0.0f;
  bool variances = false;     // fill variance buffers with the true noise variances
  unsigned seed = 1;
  // The content pans by (pan_x, pan_y) whole pixels per frame; with
  // follow_motion the temporal buffers follow it (GradientFrame::temporal_target
  // = the pan), otherwise they are the same-pixel differences.
  int pan_x = 0, pan_y = 0;
  bool follow_motion = false;
};


inline Image exact_frame(int w, int h, int t, int channels = 3, int pan_x = 0, int pan_y = 0) {
  Image img(w, h, channels);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < channels; ++c) img.at(x, y, c) = scene_value(x - pan_x * t, y - pan_y * t, t, c);
  return img;
}

// Frame t's buffers; the temporal buffers of the last frame are filled from
// frame t+1 of the scene anyway: the window must ignore them.
inline GradientWindow make_window(const SceneOptions& o) {
  std::mt19937 rng(o.seed);
  std::normal_distribution<float> gauss(0.0f, 1.0f);
  GradientWindow win;
  for (int t = 0; t < o.frames; ++t) {
    auto f = std::make_shared<GradientFrame>();
    const Image cur = exact_frame(o.width, o.height, t, o.channels, o.pan_x, o.pan_y);
    const Image next = exact_frame(o.width, o.height, t + 1, o.channels, o.pan_x, o.pan_y);
    // Where the temporal terms of (x, y) land in the next frame (clamped:
    // the window drops a constraint whose target leaves the image).
    const int ox = o.follow_motion ? o.pan_x : 0, oy = o.follow_motion ? o.pan_y : 0;
    if (o.temporal && o.follow_motion) {
      f->temporal_target = Image(o.width, o.height, 2);
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x) {
          f->temporal_target.at(x, y, 0) = float(ox);
          f->temporal_target.at(x, y, 1) = float(oy);
        }
    }
    for (Term term : kAllTerms) {
      if (is_temporal(term) && !o.temporal) continue;
      Image& b = f->buffer(term);
      b = Image(o.width, o.height, o.channels);
      const float sigma = term == Term::kPrimal ? o.primal_sigma : o.gradient_sigma;
      for (int y = 0; y < o.height; ++y)
        for (int x = 0; x < o.width; ++x)
          for (int c = 0; c < o.channels; ++c) {
            const int xr = std::min(x + 1, o.width - 1), yd = std::min(y + 1, o.height - 1);
            const auto dx = [&](const Image& I) { return I.at(xr, y, c) - I.at(x, y, c); };
            const auto dy = [&](const Image& I) { return I.at(x, yd, c) - I.at(x, y, c); };
            const int tx = std::clamp(x + ox, 0, o.width - 1), ty = std::clamp(y + oy, 0, o.height - 1);
            const int txr = std::min(tx + 1, o.width - 1), tyd = std::min(ty + 1, o.height - 1);
            const float next_dx = next.at(txr, ty, c) - next.at(tx, ty, c);
            const float next_dy = next.at(tx, tyd, c) - next.at(tx, ty, c);
            float v = 0;
            switch (term) {
              case Term::kPrimal: v = cur.at(x, y, c); break;
              case Term::kDx: v = dx(cur); break;
              case Term::kDy: v = dy(cur); break;
              case Term::kDt: v = next.at(tx, ty, c) - cur.at(x, y, c); break;
              case Term::kDxdt: v = next_dx - dx(cur); break;
              case Term::kDydt: v = next_dy - dy(cur); break;
            }
            b.at(x, y, c) = v + sigma * gauss(rng);
          }
      if (o.variances) {
        Image& var = f->variance(term);
        var = Image(o.width, o.height, o.channels);
        for (float& v : var.data()) v = sigma * sigma;
      }
    }
    win.frames.push_back(std::move(f));
  }
  return win;
}

// Root-mean-square and max error of `got` against the exact scene frame t.
struct ErrorStats {
  double rms = 0, max = 0;
};
inline ErrorStats frame_error(const Image& got, int t, int pan_x = 0, int pan_y = 0) {
  const Image ref = exact_frame(got.width(), got.height(), t, got.channels(), pan_x, pan_y);
  ErrorStats e;
  for (size_t i = 0; i < ref.data().size(); ++i) {
    const double d = double(got.data()[i]) - ref.data()[i];
    e.rms += d * d;
    e.max = std::max(e.max, std::fabs(d));
  }
  e.rms = std::sqrt(e.rms / ref.data().size());
  return e;
}

inline bool all_finite(const Image& img) {
  for (float v : img.data())
    if (!std::isfinite(v)) return false;
  return true;
}

inline GradientFrame& mutable_frame(GradientWindow& w, int t) {
  return const_cast<GradientFrame&>(*w.frames[t]);
}

// Tells the weighted method that the gradient buffers are exact (a tiny
// variance on every gradient term).
inline void mark_gradients_exact(GradientWindow& w) {
  for (int t = 0; t < w.size(); ++t)
    for (Term term : kAllTerms)
      if (term != Term::kPrimal && mutable_frame(w, t).has(term))
        for (float& v : mutable_frame(w, t).variance(term).data()) v = 1e-6f;
}

}  // namespace gdvr::test
