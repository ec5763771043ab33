// Mitsuba's `perspective` sensor (pinhole): camera space looks along +z with
// +x to the image's left and +y up; fov is converted to the x axis per fov_axis.
#pragma once

#include "core/math/bounds.h"
#include "core/render/ray.h"
#include "core/scene/scene.h"

namespace gdvr {

float fov_x_degrees(const Camera& camera, int width, int height);

class PerspectiveCamera {
 public:
  PerspectiveCamera(const Camera& camera, int width, int height);
  // `film` in pixel units: (0,0) is the top-left corner of the image.
  Ray generate_ray(Vec2f film) const;
  // Pixel position (continuous) where world point p projects; false if behind
  // the camera or outside the image (used by temporal reprojection).
  bool project(Vec3f p, Vec2f* film) const;
  // The film rectangle [lo, hi] that contains the image of the world box `b`
  // (the bounds of its projected corners, which contain the projection of
  // the whole box while it lies beyond the near plane). False when part of
  // the box is not beyond the near plane: its image is then unbounded.
  bool project_bounds(const Bounds3f& b, Vec2f* lo, Vec2f* hi) const;

 private:
  Transform to_world_, to_camera_;
  Vec3f origin_;
  Vec3f dir_at_origin_, dir_per_x_, dir_per_y_;  // unnormalised world direction at film (x, y): at_origin + x per_x + y per_y
  float inv_width_, inv_height_, tan_half_x_, tan_half_y_, near_, far_;
  int width_, height_;
};

}  // namespace gdvr
