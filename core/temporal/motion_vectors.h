// Motion vectors by primary-hit reprojection (Manzi et al. 2016 and their
// public release; docs/tgpt.md): trace the camera ray through each pixel centre at
// frame t, carry the hit point with its shape's motion to the other frame's
// time (x' = T_other · T_t⁻¹ · x) and project it with the other frame's
// camera. The offset keeps its fraction (the motion-compensated replay rotates
// sub-pixel positions by it, core/temporal/replay_map.h); whoever needs a
// pixel rounds it with motion_pixel_offset. A forward/backward check then
// decides where a same-pixel temporal constraint is trusted.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/image/image.h"
#include "core/render/frame_scene.h"
#include "core/scene/scene.h"
#include "core/temporal/tgpt_settings.h"

namespace gdvr {

// Three channels per pixel: X, Y = offset (pixels, fractional, +x right, +y
// down) from the pixel centre to where the surface seen through it lies in the
// other frame; V = 1 if it projects into the other frame's image, else 0
// (X = Y = 0).
struct MotionField {
  Image offsets;
  uint64_t rays = 0;  // primary rays traced (one per pixel)
};

// The one rounding rule of motion offsets: the whole-pixel offset of the pixel
// whose footprint [x, x+1) holds the landing point x + 0.5 + m of a pixel
// centre moved by m (ties, m = k + 0.5, go to the right/lower pixel, as the
// footprint is half-open). Every consumer of a motion field rounds with it,
// so that stage 1 (the replay map) and stage 2 (the temporal pairs) agree.
inline int motion_pixel_offset(float m) { return int(std::floor(m + 0.5f)); }

// `scene` is frame t (its accelerator at t's time); `desc_t` and `desc_other`
// are the animated descriptions of frame t and of the frame to reproject to.
MotionField compute_motion_field(const FrameScene& scene, const Scene& desc_t, const Scene& desc_other, int width,
                                 int height, int threads);

// Where the same-pixel temporal constraint between frames t and t+1 holds
// (docs/tgpt.md, "dt and motion"): `forward` is frame t's field towards t+1,
// `backward` frame t+1's field towards t. A pixel p passes if, both ways, its
// surface projects into the other image, the round trip p → p + m(p) → back
// returns within ±consistency_tolerance_px (per axis), and |m(p)| ≤
// max_same_pixel_motion_px (per axis, when ≥ 0).
struct TemporalMask {
  std::vector<uint8_t> valid;  // width*height, 1 = keep the pixel's dt, dxdt, dydt
  Image failure;               // one channel: 1 where the constraint was dropped
  int64_t failed = 0;
};
TemporalMask temporal_consistency(const Image& forward, const Image& backward, const TgptSettings& settings);

}  // namespace gdvr
