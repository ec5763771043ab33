// The motion-compensated replay of T-GPT (Manzi et al. 2016; docs/tgpt.md,
// "dt and motion"): which sample stream of the previous frame's pass B each
// pixel's pass-A sample replays, and by how much it rotates that sample's
// sub-pixel position.
//
// Pass B of frame t and pass A of frame t+1 share a stream keyed by pixel
// (pass_schedule.h). Replayed at the same pixel, the pair only stays
// correlated while the surface under the pixel stays the same; on a pan over
// texture it does not. With the map, pixel q of frame t+1 replays the stream
// of the pixel its surface came from, s(q) = q + round(b(q)) (b the backward
// motion field, rounded with motion_pixel_offset), and where that sample drew
// the sub-pixel position u ∈ [0,1)² at s(q), q uses
//   u_A = frac(u + δ),  δ = s(q) − q − b(q) ∈ (−0.5, 0.5]² (per axis):
// the film point q + u + δ is where s(q) + u lands after the motion, so the
// replayed path starts at the same surface point wherever u + δ stays inside
// [0,1). u_A is still uniform over q's pixel and the rest of the stream is
// still independent of the scene, so pass A stays an unbiased estimate of
// frame t+1 pixel by pixel; only its pairing with pass B changes. Stage 2
// (temporal_gradients) pairs A_{t+1}(q) with B_t(p) exactly where s(q) = p.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/image/image.h"
#include "core/math/vec.h"

namespace gdvr {

struct ReplaySource {
  uint32_t x = 0, y = 0;  // the pixel whose stream this pixel's samples replay
  Vec2f shift{0.0f, 0.0f};  // δ, added to that stream's sub-pixel position modulo 1
};

// One source per pixel, row-major. A default (empty) map is no map.
struct ReplayMap {
  int width = 0, height = 0;
  std::vector<ReplaySource> sources;

  bool empty() const { return sources.empty(); }
  const ReplaySource& at(int x, int y) const { return sources[size_t(y) * size_t(width) + size_t(x)]; }
};

// frac(u + shift) for u ∈ [0,1), shift ∈ (−1, 1): always in [0,1) (a tiny
// negative sum would round to 1 after adding 1; it wraps to 0 instead).
inline float rotate_unit(float u, float shift) {
  float v = u + shift;
  v -= std::floor(v);
  return v < 1.0f ? v : 0.0f;
}
inline Vec2f rotate_jitter(Vec2f u, Vec2f shift) { return {rotate_unit(u.x, shift.x), rotate_unit(u.y, shift.y)}; }

// The map of pass A of a frame from its backward motion field (three
// channels X, Y, V towards the previous frame, compute_motion_field). A pixel
// whose field is invalid (V = 0) or whose source lies outside the image
// replays its own stream unrotated, as without a map.
ReplayMap build_replay_map(const Image& backward);

// Where pixel q's pass-A sample comes from under `backward`: true with s(q) in
// (*sx, *sy), or false where q has no source (field invalid, s(q) outside the
// image) and replays its own stream. build_replay_map and stage 2 both ask
// it, so that they pair exactly the same pixels.
bool replay_source_pixel(const Image& backward, int qx, int qy, int* sx, int* sy);

// Stage 2's side of the map: the replayed pairs of frames t and t+1. Pixel p of
// frame t (`forward`, its field towards t+1) lands on q = p + round(f(p)) in
// frame t+1 (`backward`, that frame's field towards t); the pair (p, q) holds
// where f is valid at p, q lies in the image, and q's source is exactly p
// (replay_source_pixel), i.e. where pass A at q replayed pass B's stream at p.
// There is no limit on the motion: the pair follows it. Every q has one
// source, so no two pairs share a q. The images may be a region of the frames
// (a tile): a q outside it is dropped.
struct ReplayPairs {
  std::vector<uint8_t> valid;  // width*height, 1 = p has its pair
  Image target;                // two channels X, Y: q − p in whole pixels, 0 where not valid
  Image failure;               // one channel: 1 where p has none
  int64_t failed = 0;
};
ReplayPairs replay_pairs(const Image& forward, const Image& backward);

}  // namespace gdvr
