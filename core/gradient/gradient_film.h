// Per-pixel accumulators of G-PT and the named buffers made from them
// (named buffers, not magic indices: docs/architecture.md).
//
// Every base pixel owns the gradient estimates of its four offsets, so tiles
// never write to a neighbour's pixel and the result does not depend on thread
// count or tile order: dx(p) = right(p) + left(p + e_x), dy(p) = down(p) +
// up(p + e_y), each side being one MIS-weighted generation of the pair
// (Kettunen et al. 2015, Eq. 6). The primal is the base path's plain estimate
// by default (docs/gpt.md explains the choice) or the MIS-weighted pair
// primal: the mean over the pixel's neighbours j of the pair (p, j)'s two
// generations' weighted estimates of I(p), each pixel again owning the sums
// its own samples made. Sums are split by sample-index parity
// into two half buffers, whose difference gives per-pixel variances.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"

namespace gdvr {

enum class OffsetDir : int { kRight = 0, kLeft, kDown, kUp };
constexpr int kOffsetCount = 4;
constexpr std::array<int, kOffsetCount> kOffsetDx = {1, -1, 0, 0};
constexpr std::array<int, kOffsetCount> kOffsetDy = {0, 0, 1, -1};

// One sample's contribution to its base pixel.
struct GradientSample {
  Rgb primal;                               // indirect part of the base path (direct excluded)
  Rgb direct;                               // emitters seen directly from the camera
  std::array<Rgb, kOffsetCount> gradient;   // towards I(neighbour) - I(p) for right/down, I(p) - I(neighbour) for left/up
  int shifts = 0, failures = 0;             // offsets attempted and failed
  // The pair primal (GptSettings::pair_primal), per offset direction: this
  // pixel's own estimate weighted for the pair with that neighbour, and the
  // estimate its offset adds to the neighbour (both corrected for the
  // cached-path roulette, see GradientTracer::sample).
  std::array<Rgb, kOffsetCount> pair_base, pair_offset;
  // The temporal path-space shift into another frame t' (when enabled): this
  // generation's estimate of I_t'(p) - I_t(p), and whether the shift failed.
  Rgb temporal;
  bool temporal_failed = false;
};

struct GradientFilmBuffers {
  Image primal, dx, dy, direct;             // means, RGB
  Image primal_var, dx_var, dy_var;         // variance of the means, RGB, from the half buffers
  Image shift_failure_rate;                 // one channel: failed / attempted offsets
  // Only with the pair primal (GradientFilm(w, h, t, true)): its mean and the
  // variance of the mean; gpt_integrator puts them in place of primal.
  Image pair_primal, pair_primal_var;
  // Only with a temporal target (GradientFilm(w, h, true)): the mean of
  // GradientSample::temporal, its variance, and the failed fraction.
  Image temporal, temporal_var, temporal_failure_rate;
};

class GradientFilm {
 public:
  // The sums are held in bands of rows, each at least this large: resolve()
  // frees a band as soon as the rows after it no longer read it, so the
  // buffers it writes replace the sums instead of adding to them (stage 1's
  // peak; docs/tgpt.md "Memory").
  static constexpr size_t kBandBytes = size_t(32) << 20;

  GradientFilm() = default;
  GradientFilm(int width, int height, bool temporal = false, bool pair_primal = false);

  int width() const { return width_; }
  int height() const { return height_; }

  // Not thread-safe per pixel: one tile owns the pixel.
  void add(int x, int y, uint32_t sample_index, const GradientSample& s);
  // Means over `spp` samples per pixel (sample indices 0..spp-1). Consumes
  // the sums: the film holds nothing afterwards (bytes() == 0).
  GradientFilmBuffers resolve(int spp);

  // The bytes of sums the film holds now, and what a film of these settings
  // holds per pixel before resolve(): the memory accounting of stage 1.
  size_t bytes() const;
  static size_t bytes_per_pixel(bool temporal, bool pair_primal);

 private:
  struct Sums {
    double primal[3] = {0, 0, 0}, direct[3] = {0, 0, 0};
    double grad[kOffsetCount][3] = {};
    // Even sample indices only ("half A"); half B = total - A.
    double primal_a[3] = {0, 0, 0};
    double grad_a[kOffsetCount][3] = {};
    uint32_t shifts = 0, failures = 0;
  };
  // Only with a temporal target (temporal_shift reconnect): kept apart, so
  // that the passes without one (every pass of replay, G-PT) do not carry
  // them (56 bytes a pixel beside the 272 of Sums).
  struct TemporalSums {
    double temporal[3] = {0, 0, 0}, temporal_a[3] = {0, 0, 0};
    uint32_t failures = 0;
  };
  // The pair primal's sums (allocated only when it is on): the pixel's own
  // weighted estimates summed over its existing neighbours, and per direction
  // what its offsets add to each neighbour; both with half-A copies.
  struct PairSums {
    double base[3] = {0, 0, 0}, base_a[3] = {0, 0, 0};
    double into[kOffsetCount][3] = {}, into_a[kOffsetCount][3] = {};
  };
  Sums& sums(int x, int y) { return bands_[size_t(y / band_rows_)][size_t(y % band_rows_) * width_ + x]; }
  void resolve_pair_primal(int spp, GradientFilmBuffers* b) const;
  int width_ = 0, height_ = 0;
  bool temporal_ = false;
  int band_rows_ = 1;
  std::vector<std::vector<Sums>> bands_;  // band_rows_ rows each, the last one what is left
  std::vector<TemporalSums> temporal_sums_;
  std::vector<PairSums> pairs_;
};

}  // namespace gdvr
