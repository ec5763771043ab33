// Keyframed animation of to_world transforms. A track targets the sensor
// ("sensor") or a shape/emitter by id. Frame f of a job is evaluated at time
// f / fps. Translation and scale interpolate linearly (or Catmull-Rom cubic),
// rotation by quaternion slerp.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/math/transform.h"
#include "core/scene/scene.h"
#include "core/util/status.h"

namespace gdvr {

enum class Interpolation { kStep, kLinear, kCubic };

struct Keyframe {
  double time = 0;      // seconds
  Transform to_world;   // full transform at this key (from a matrix or a lookat)
};

// A transform computed from a richer animation model than whole-transform keys
// (a glTF node graph: T/R/S channels on the node and every ancestor). Key
// interpolation cannot reproduce such motion exactly, so a track may carry one.
class TransformCurve {
 public:
  virtual ~TransformCurve() = default;
  virtual Transform evaluate(double time) const = 0;
};

struct Track {
  std::string target;   // "sensor" or a shape/emitter id
  Interpolation interpolation = Interpolation::kLinear;
  std::vector<Keyframe> keys;  // sorted by time, at least one
  // When set, evaluate_track returns curve->evaluate(time) and `keys` are only
  // samples of it (at the source's own key times) for validation and tools.
  std::shared_ptr<const TransformCurve> curve;
};

struct Animation {
  std::vector<Track> tracks;
  bool empty() const { return tracks.empty(); }
};

// Interpolated transform of a track at `time` (clamped to the first/last key).
Transform evaluate_track(const Track& track, double time);
// Checks that every track names an existing target and has sorted, finite keys.
Status validate_animation(const Animation& anim, const Scene& scene);
// Writes the tracks' transforms at `time` into the scene's shapes, emitters, camera.
Status apply_animation(const Animation& anim, double time, Scene* scene);

}  // namespace gdvr
