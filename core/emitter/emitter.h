// Emitters of the Mitsuba 3 subset: area (one-sided, attached to a shape),
// point, spot, directional, constant environment and importance-sampled
// environment map. Data only: each kind's sampling is in a file of its own
// here (area_emitter.h, point_emitter.h, directional_emitter.h,
// environment_emitter.h); FrameScene picks the emitter and hands them the
// frame's world-space geometry.
#pragma once

#include <memory>
#include <string>

#include "core/image/image.h"
#include "core/math/transform.h"
#include "core/math/vec.h"

namespace gdvr {

enum class EmitterType { kArea, kPoint, kSpot, kDirectional, kConstant, kEnvmap };

struct Emitter {
  std::string id;
  EmitterType type = EmitterType::kArea;
  Rgb radiance{1.0f};     // area, constant
  Rgb intensity{1.0f};    // point, spot (W/sr)
  Rgb irradiance{1.0f};   // directional
  Transform to_world;     // point/spot placement, directional (+z is the travel direction), envmap rotation
  float cutoff_angle = 20.0f;  // spot, degrees
  float beam_width = 15.0f;    // spot, degrees (Mitsuba default: 3/4 of cutoff)
  float scale = 1.0f;          // envmap radiance scale
  std::shared_ptr<const Image> envmap;  // lat-long, linear RGB
  int shape = -1;              // area: index into Scene::shapes

  bool is_delta_position() const { return type == EmitterType::kPoint || type == EmitterType::kSpot; }
  bool is_delta_direction() const { return type == EmitterType::kDirectional; }
  bool is_infinite() const {
    return type == EmitterType::kConstant || type == EmitterType::kEnvmap || type == EmitterType::kDirectional;
  }
};

}  // namespace gdvr
