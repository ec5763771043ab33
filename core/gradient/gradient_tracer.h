// The per-thread G-PT tracer: one base path through pixel p and its offsets
// into the four neighbours (same sub-pixel position shifted by one pixel),
// with the shift mapping of the settings. Owns its scratch storage, so the
// per-sample loop does not allocate once the path record has grown.
#pragma once

#include "core/gradient/camera_hit_cache.h"
#include "core/gradient/gpt_settings.h"
#include "core/gradient/gradient_film.h"
#include "core/gradient/path_record.h"
#include "core/gradient/temporal_reconnection_shift.h"
#include "core/gradient/tile_camera_rays.h"
#include "core/render/path_tracer.h"
#include "core/render/perspective_camera.h"

namespace gdvr {

struct ReplayMap;  // core/temporal/replay_map.h

class GradientTracer {
 public:
  GradientTracer(const FrameScene& scene, const PerspectiveCamera& camera, int width, int height,
                 const PathTracerSettings& path, const GptSettings& settings, uint64_t seed, uint32_t frame);

  // Starts sample index s of the pixels of `tile`; sample() then takes them
  // in any order. With GptSettings::shared_jitter the first hits of the tile's
  // camera rays (and of the ring around it) are traced once and shared by
  // base paths and offsets (CameraHitCache); without it every pixel's own
  // base ray, and where every offset is made (no cached-path roulette, a
  // shift that starts from the first hit) the offsets' rays too, are traced
  // up front in streams (TileCameraRays).
  void begin_sample(const Tile& tile, uint32_t s);
  // One sample of pixel (x, y) of the current tile with the current sample
  // index: the base estimate, the four MIS-weighted gradient generations
  // (divided by the cached-path RR probability) and the shift statistics.
  void sample(int x, int y, GradientSample* out);

  const PathCounters& counters() const { return counters_; }
  // Also shift every base path into another frame (T-GPT's path-space
  // temporal shift); null: spatial offsets only.
  void set_temporal_target(const TemporalShiftTarget* target) { temporal_ = target; }
  uint64_t temporal_rays() const { return temporal_rays_; }  // part of counters().rays
  // T-GPT's motion-compensated replay: each pixel draws the stream of its
  // map entry's source pixel and rotates that stream's sub-pixel position by
  // the entry's shift (its offsets into the neighbours use the same rotated
  // position). Null: every pixel its own stream, unrotated. Under
  // GptSettings::shared_jitter only the stream follows the map: the shared
  // position is the tile's, not the pixel's.
  void set_replay_map(const ReplayMap* map) { replay_ = map; }

 private:
  const FrameScene& scene_;
  const PerspectiveCamera& camera_;
  const int width_, height_;
  const PathTracerSettings& path_;
  const GptSettings& settings_;
  const uint64_t seed_;
  const uint32_t frame_;
  PathCounters counters_;
  PathRecord base_;
  uint32_t s_ = 0;       // the current sample index
  Vec2f shared_jitter_;  // its sub-pixel position when shared
  CameraHitCache camera_hits_;
  TileCameraRays tile_rays_;
  bool tile_offsets_ = false;  // tile_rays_ holds the offsets' rays
  // Pixel (x, y)'s own sub-pixel position for the current sample index, and
  // its sampler just after drawing it (the rest of the stream is its paths').
  Vec2f own_jitter(int x, int y, Sampler* sampler) const;
  const TemporalShiftTarget* temporal_ = nullptr;
  uint64_t temporal_rays_ = 0;
  const ReplayMap* replay_ = nullptr;
};

}  // namespace gdvr
