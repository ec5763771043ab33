// Affine/projective 4x4 transforms with a cached inverse. Stored in double so
// that chains of Mitsuba <transform> elements and keyframe interpolation do not
// lose precision before the result is used in float geometry.
#pragma once

#include <array>
#include <string>

#include "core/math/vec.h"

namespace gdvr {

struct Matrix4 {
  std::array<std::array<double, 4>, 4> m{};  // row-major: m[row][col]

  static Matrix4 identity();
  Matrix4 operator*(const Matrix4& o) const;
  // Returns false when singular (or not finite); `out` is then untouched.
  bool inverse(Matrix4* out) const;
  Matrix4 transpose() const;
  bool is_finite() const;
  bool operator==(const Matrix4& o) const { return m == o.m; }
};

class Transform {
 public:
  Transform() : m_(Matrix4::identity()), inv_(Matrix4::identity()) {}
  // Fails (returns false) for singular or non-finite matrices.
  static bool from_matrix(const Matrix4& m, Transform* out);
  static Transform translate(Vec3f d);
  static Transform scale(Vec3f s);  // caller guarantees non-zero components
  static Transform rotate(Vec3f axis, float angle_degrees);
  // Mitsuba's <lookat>: camera looks along +z towards target, +y up, to_world.
  // Returns false for degenerate input (origin == target, up parallel to view).
  static bool look_at(Vec3f origin, Vec3f target, Vec3f up, Transform* out);

  Transform operator*(const Transform& o) const;  // (a*b)(p) = a(b(p))
  Transform inverse() const;

  Vec3f point(Vec3f p) const;
  Vec3f vector(Vec3f v) const;
  Vec3f normal(Vec3f n) const;  // inverse transpose; result not normalised

  const Matrix4& matrix() const { return m_; }
  const Matrix4& inverse_matrix() const { return inv_; }
  bool is_identity() const { return m_ == Matrix4::identity(); }
  bool operator==(const Transform& o) const { return m_ == o.m_; }
  bool operator!=(const Transform& o) const { return !(m_ == o.m_); }
  std::string to_string() const;

 private:
  Transform(const Matrix4& m, const Matrix4& inv) : m_(m), inv_(inv) {}
  Matrix4 m_, inv_;
};

}  // namespace gdvr
