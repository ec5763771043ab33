#include "core/render/perspective_camera.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gdvr {

float fov_x_degrees(const Camera& camera, int width, int height) {
  double aspect = double(width) / double(height);
  double t = std::tan(double(radians(camera.fov)) * 0.5);
  FovAxis axis = camera.fov_axis;
  if (axis == FovAxis::kSmaller) axis = aspect > 1 ? FovAxis::kY : FovAxis::kX;
  if (axis == FovAxis::kLarger) axis = aspect > 1 ? FovAxis::kX : FovAxis::kY;
  double tx = t;
  if (axis == FovAxis::kY) tx = t * aspect;
  if (axis == FovAxis::kDiagonal) tx = t / std::sqrt(1.0 + 1.0 / (aspect * aspect));
  return float(2.0 * std::atan(tx) * 180.0 / M_PI);
}

PerspectiveCamera::PerspectiveCamera(const Camera& camera, int width, int height)
    : to_world_(camera.to_world), to_camera_(camera.to_world.inverse()), width_(width), height_(height) {
  origin_ = to_world_.point(Vec3f(0.0f));
  inv_width_ = 1.0f / float(width);
  inv_height_ = 1.0f / float(height);
  tan_half_x_ = std::tan(radians(fov_x_degrees(camera, width, height)) * 0.5f);
  tan_half_y_ = tan_half_x_ * float(height) / float(width);
  near_ = camera.near_clip;
  far_ = camera.far_clip;
  // The camera-space direction through film point (fx, fy) on the z = 1 plane
  // is affine in (fx, fy); so is its world-space image. Precomputed once: a
  // ray then costs two multiply-adds per axis instead of a matrix product.
  const Vec3f ax = to_world_.vector({tan_half_x_, 0.0f, 0.0f}), ay = to_world_.vector({0.0f, tan_half_y_, 0.0f});
  dir_at_origin_ = ax + ay + to_world_.vector({0.0f, 0.0f, 1.0f});
  dir_per_x_ = ax * (-2.0f * inv_width_);
  dir_per_y_ = ay * (-2.0f * inv_height_);
}

Ray PerspectiveCamera::generate_ray(Vec2f film) const {
  float sx = film.x * inv_width_, sy = film.y * inv_height_;
  // The camera-space direction on the z = 1 plane, whose length is 1 / cos of
  // the angle to the axis: the distance to the clip planes along the ray. The
  // world direction (to_world may scale) is normalised once.
  const Vec3f local((1.0f - 2.0f * sx) * tan_half_x_, (1.0f - 2.0f * sy) * tan_half_y_, 1.0f);
  const float inv_z = length(local);
  Ray ray;
  ray.o = origin_;
  ray.d = normalize(dir_at_origin_ + dir_per_x_ * film.x + dir_per_y_ * film.y);
  ray.tmin = near_ * inv_z;
  ray.tmax = far_ * inv_z;
  return ray;
}

bool PerspectiveCamera::project(Vec3f p, Vec2f* film) const {
  Vec3f local = to_camera_.point(p);
  if (!(local.z > near_)) return false;
  float sx = 0.5f * (1.0f - local.x / (local.z * tan_half_x_));
  float sy = 0.5f * (1.0f - local.y / (local.z * tan_half_y_));
  *film = {sx * float(width_), sy * float(height_)};
  return film->x >= 0 && film->y >= 0 && film->x < float(width_) && film->y < float(height_);
}

bool PerspectiveCamera::project_bounds(const Bounds3f& b, Vec2f* lo, Vec2f* hi) const {
  if (b.empty()) return false;
  *lo = Vec2f(std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity());
  *hi = Vec2f(-std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity());
  for (int i = 0; i < 8; ++i) {
    const Vec3f local = to_camera_.point(b.corner(i));
    if (!(local.z > near_)) return false;
    const Vec2f film(0.5f * (1.0f - local.x / (local.z * tan_half_x_)) * float(width_),
                     0.5f * (1.0f - local.y / (local.z * tan_half_y_)) * float(height_));
    lo->x = std::min(lo->x, film.x), lo->y = std::min(lo->y, film.y);
    hi->x = std::max(hi->x, film.x), hi->y = std::max(hi->y, film.y);
  }
  return std::isfinite(lo->x) && std::isfinite(lo->y) && std::isfinite(hi->x) && std::isfinite(hi->y);
}

}  // namespace gdvr
