// The path-space temporal shift of T-GPT (docs/tgpt.md, "The path-space
// temporal shift"): Kettunen et al. 2015's reconnection shift carried across
// frames, with its Jacobian and MIS, as the alternative to the random replay
// that Manzi et al. 2016 use for temporal gradients. A base
// path of frame t, cached, is shifted into another frame t' (t ± 1) with its
// scene, lights and camera at t'.
//
//   y_1      the t' camera's ray through the base's film position (the same
//            pixel and sub-pixel offset; Jacobian 1 on the film);
//   prefix   while no reconnection is possible the offset follows the base as
//            the spatial reconnection shift does (same Dirac lobe, half-vector
//            copy), tracing in frame t';
//   y_{k+1} = M(x_{k+1}) once x_k, y_k and x_{k+1} are diffuse: the offset
//            reconnects to the base's next vertex carried with its shape's
//            motion M (shape_motion.h), and every later vertex is carried the
//            same way. The carried vertex's area Jacobian is 1 for rigid
//            motions, so each carried segment contributes the reconnection
//            factor (cos'_y/cos_y)(d²/d'²) of the spatial reconnection
//            shift (docs/gpt.md, "Shift mappings").
//
// Unlike the spatial shift, the carried suffix is not shared with the base:
// every segment is tested for visibility in frame t' (another object may have
// moved into it), the BSDF is re-evaluated wherever a direction changed, and
// emitter sampling repeats the base's light sample in frame t'. A segment
// whose two ends move together, entered along a direction that moved with
// them, is carried rigidly: same f, pdfs and MIS weights, one visibility ray.
// A Dirac vertex whose directions change fails (finite difference, as every
// failure: offset 0, weight 1). MIS per technique with the balance heuristic
// on the accumulated ratio p'(T x)|J| / p(x) (double), exactly as the spatial
// pairs; the reverse generation is the frame t' base path shifted back to t.
#pragma once

#include <vector>

#include "core/gradient/gpt_settings.h"
#include "core/gradient/shape_motion.h"
#include "core/gradient/shift_mapping.h"
#include "core/render/path_tracer.h"
#include "core/render/perspective_camera.h"

namespace gdvr {

// The frame a temporal shift goes to.
struct TemporalShiftTarget {
  const FrameScene* scene = nullptr;          // frame t' (accelerator at its time)
  const PerspectiveCamera* camera = nullptr;  // frame t''s camera, same resolution
  const ShapeMotion* motion = nullptr;        // frame t -> t'
};

// `base` was traced in `scene` (frame t) from film position `film`. The
// result's gradient estimates I_t'(p) − I_t(p) (indirect part) from this
// generation. `trace` (tests) receives every technique's ratio in order and
// the offset path as a record, so the shift can be applied backwards.
ShiftResult temporal_reconnection_shift(const FrameScene& scene, const GptSettings& settings, const PathRecord& base,
                                        Vec2f film, const TemporalShiftTarget& target, PathCounters& counters,
                                        ShiftTrace* trace = nullptr);

}  // namespace gdvr
