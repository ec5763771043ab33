// Motion vectors by primary-hit reprojection (Manzi et al. 2016 and their
// public release; docs/tgpt.md): trace the camera ray through each pixel centre at
// frame t, carry the hit point with its shape's motion to the other frame's
// time (x' = T_other · T_t⁻¹ · x), project it with the other frame's camera and
// round the offset to whole pixels. A forward/backward check then decides
// where a temporal constraint is trusted.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image/image.h"
#include "core/render/frame_scene.h"
#include "core/scene/scene.h"
#include "core/temporal/tgpt_settings.h"

namespace gdvr {

// Three channels per pixel: X, Y = rounded offset (pixels, +x right, +y down)
// to where the surface seen through the pixel centre lies in the other frame;
// V = 1 if it projects into the other frame's image, else 0 (X = Y = 0).
struct MotionField {
  Image offsets;
  uint64_t rays = 0;  // primary rays traced (one per pixel)
};

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
