#include "core/gradient/gradient_tracer.h"

#include <algorithm>

#include "core/gradient/base_path.h"
#include "core/gradient/reconnection_shift.h"
#include "core/gradient/replay_shift.h"
#include "core/temporal/replay_map.h"

namespace gdvr {

GradientTracer::GradientTracer(const FrameScene& scene, const PerspectiveCamera& camera, int width, int height,
                               const PathTracerSettings& path, const GptSettings& settings, uint64_t seed,
                               uint32_t frame)
    : scene_(scene), camera_(camera), width_(width), height_(height), path_(path), settings_(settings),
      seed_(seed), frame_(frame), camera_hits_(scene, camera), tile_rays_(scene, camera) {
  base_.v.reserve(64);
}

Vec2f GradientTracer::own_jitter(int x, int y, Sampler* sampler) const {
  // Whose stream this sample replays (the pixel's own without a replay map).
  const ReplaySource* source = replay_ ? &replay_->at(x, y) : nullptr;
  *sampler = Sampler(seed_, frame_, source ? source->x : uint32_t(x), source ? source->y : uint32_t(y), s_);
  const Vec2f own = sampler->next_2d();
  return source ? rotate_jitter(own, source->shift) : own;
}

void GradientTracer::begin_sample(const Tile& tile, uint32_t s) {
  s_ = s;
  if (!settings_.shared_jitter) {
    // The offsets' rays only where every offset is made and starts from its
    // first hit (the replay shift traces its own path from the ray).
    tile_offsets_ = !settings_.cached_rr && settings_.shift != ShiftMapping::kReplay;
    Sampler sampler;
    tile_rays_.begin(tile, width_, height_, [&](int x, int y) { return own_jitter(x, y, &sampler); }, tile_offsets_,
                     counters_);
    return;
  }
  // A pixel no image has (coordinates are bounded far below 2^32 - 1) keys the
  // shared position, so it is independent of every pixel's own stream.
  Sampler shared(seed_, frame_, ~0u, ~0u, s);
  shared_jitter_ = shared.next_2d();
  camera_hits_.begin(tile, shared_jitter_, counters_);
}

void GradientTracer::sample(int x, int y, GradientSample* out) {
  *out = GradientSample();
  // Box filter, as render_frame_pt. The pixel's own position is drawn even
  // when the shared one is used, so the rest of its stream stays PT's.
  Sampler sampler;
  const Vec2f own = own_jitter(x, y, &sampler);
  const bool shared = settings_.shared_jitter;
  const Vec2f jitter = shared ? shared_jitter_ : own;
  const Sampler after_camera = sampler;
  trace_base_path(scene_, path_, shared ? camera_hits_.at(x, y, counters_) : tile_rays_.base(x, y), sampler, counters_,
                  &base_);
  if (base_.invalid) return;
  out->primal = base_.indirect;
  out->direct = base_.direct;
  // The pair primal where no shift is made (the roulette said no, or no
  // neighbour): the base's own estimate, nothing into the neighbour.
  out->pair_base.fill(base_.indirect);

  // ---- The temporal offset (every base path: no cached-path roulette) ----
  if (temporal_) {
    const uint64_t rays_before = counters_.rays;
    const ShiftResult t =
        temporal_reconnection_shift(scene_, settings_, base_, {float(x) + jitter.x, float(y) + jitter.y}, *temporal_,
                                    counters_);
    temporal_rays_ += counters_.rays - rays_before;
    out->temporal = t.gradient;
    out->temporal_failed = t.failed;
    if (!is_finite(out->temporal)) {
      ++counters_.invalid_samples;
      out->temporal = Rgb(0.0f);
    }
  }

  // ---- Cached-path Russian roulette (§3.3): shift with probability q, divide by q ----
  float inv_q = 1.0f;
  if (settings_.cached_rr) {
    const float q = std::max(std::min(1.0f, luminance(base_.indirect)), settings_.cached_rr_min_q);
    if (q < 1.0f) {
      if (sampler.next_1d() >= q) return;
      inv_q = 1.0f / q;
    }
  }

  // ---- Offsets into the four neighbours ----
  for (int o = 0; o < kOffsetCount; ++o) {
    const int nx = x + kOffsetDx[size_t(o)], ny = y + kOffsetDy[size_t(o)];
    if (nx < 0 || ny < 0 || nx >= width_ || ny >= height_) continue;
    const auto offset_ray = [&] { return camera_.generate_ray({float(nx) + jitter.x, float(ny) + jitter.y}); };
    const bool replay_prefix = settings_.shift == ShiftMapping::kHybrid;
    ShiftResult r;
    if (settings_.shift == ShiftMapping::kReplay) {
      // Replay re-traces the whole offset path from its camera ray (trace_path).
      r = replay_shift(scene_, path_, base_, offset_ray(), after_camera, counters_);
    } else if (shared) {
      r = shift_from_cache(scene_, settings_, base_, camera_hits_.at(nx, ny, counters_), replay_prefix, counters_);
    } else if (tile_offsets_) {
      r = shift_from_cache(scene_, settings_, base_, tile_rays_.offset(x, y, o), replay_prefix, counters_);
    } else {
      r = shift_from_cache(scene_, settings_, base_, offset_ray(), replay_prefix, counters_);
    }
    // Right/down estimate I(j) - I(p); left/up slots hold I(p) - I(j) (film convention).
    const float sign = (o == int(OffsetDir::kRight) || o == int(OffsetDir::kDown)) ? 1.0f : -1.0f;
    Rgb g = r.gradient * (sign * inv_q);
    if (!is_finite(g)) {
      ++counters_.invalid_samples;
      g = Rgb(0.0f);
    }
    out->gradient[size_t(o)] = g;
    // The pair primal under the roulette: A - (A - B) / q estimates B (the
    // base's weighted share) and C / q the offset's, C = Σ w c_o; both are
    // what the pair's weights give when the shift is always made.
    const Rgb a = base_.indirect;
    Rgb pb = a - (a - r.base_weighted) * inv_q, po = r.offset_primal * inv_q;
    if (!is_finite(pb) || !is_finite(po)) pb = a, po = Rgb(0.0f);  // (the gradient check above counts it)
    out->pair_base[size_t(o)] = pb;
    out->pair_offset[size_t(o)] = po;
    ++out->shifts;
    if (r.failed) ++out->failures;
  }
}

}  // namespace gdvr
