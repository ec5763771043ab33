// Small fixed-size vector and colour types used throughout the renderer.
// Geometry is float (what Embree traces); pdf ratios and Jacobians use double
// where the gradient-domain code needs them: products of pdfs over long or
// glossy paths under- and overflow in float (docs/stability.md).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace gdvr {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInvSqrtPi = 0.56418958354775628695f;
constexpr float kInvTwoPi = 0.15915494309189533577f;
constexpr float kInvFourPi = 0.07957747154594766788f;

inline float radians(float deg) { return deg * (kPi / 180.0f); }
inline float safe_sqrt(float x) { return std::sqrt(std::max(0.0f, x)); }
inline float sqr(float x) { return x * x; }

struct Vec2f {
  float x = 0, y = 0;
  Vec2f() = default;
  constexpr Vec2f(float x_, float y_) : x(x_), y(y_) {}
  float operator[](int i) const { return i == 0 ? x : y; }
  Vec2f operator+(Vec2f o) const { return {x + o.x, y + o.y}; }
  Vec2f operator-(Vec2f o) const { return {x - o.x, y - o.y}; }
  Vec2f operator*(float s) const { return {x * s, y * s}; }
};

struct Vec3f {
  float x = 0, y = 0, z = 0;
  Vec3f() = default;
  constexpr Vec3f(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  explicit constexpr Vec3f(float s) : x(s), y(s), z(s) {}

  float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  Vec3f operator+(Vec3f o) const { return {x + o.x, y + o.y, z + o.z}; }
  Vec3f operator-(Vec3f o) const { return {x - o.x, y - o.y, z - o.z}; }
  Vec3f operator-() const { return {-x, -y, -z}; }
  Vec3f operator*(float s) const { return {x * s, y * s, z * s}; }
  Vec3f operator/(float s) const { return *this * (1.0f / s); }
  Vec3f operator*(Vec3f o) const { return {x * o.x, y * o.y, z * o.z}; }
  Vec3f& operator+=(Vec3f o) { x += o.x; y += o.y; z += o.z; return *this; }
  Vec3f& operator-=(Vec3f o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  Vec3f& operator*=(float s) { x *= s; y *= s; z *= s; return *this; }
};
inline Vec3f operator*(float s, Vec3f v) { return v * s; }
inline float dot(Vec3f a, Vec3f b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float abs_dot(Vec3f a, Vec3f b) { return std::abs(dot(a, b)); }
inline Vec3f cross(Vec3f a, Vec3f b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length_squared(Vec3f v) { return dot(v, v); }
inline float length(Vec3f v) { return std::sqrt(dot(v, v)); }
// Normalising a zero vector is a bug upstream; return it unchanged rather than NaN.
inline Vec3f normalize(Vec3f v) {
  float l2 = dot(v, v);
  return l2 > 0.0f ? v * (1.0f / std::sqrt(l2)) : v;
}
inline Vec3f min(Vec3f a, Vec3f b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3f max(Vec3f a, Vec3f b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline float max_component(Vec3f v) { return std::max(v.x, std::max(v.y, v.z)); }
inline float max_abs_component(Vec3f v) { return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z))); }
inline bool is_finite(Vec3f v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
// Reflect wi about n (both pointing away from the surface).
inline Vec3f reflect(Vec3f wi, Vec3f n) { return 2.0f * dot(wi, n) * n - wi; }

// Linear RGB radiance / reflectance. gdvr renders in linear Rec.709 RGB like
// Mitsuba's scalar_rgb variant.
struct Rgb {
  float r = 0, g = 0, b = 0;
  Rgb() = default;
  constexpr Rgb(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
  explicit constexpr Rgb(float s) : r(s), g(s), b(s) {}

  float operator[](int i) const { return i == 0 ? r : (i == 1 ? g : b); }
  float& operator[](int i) { return i == 0 ? r : (i == 1 ? g : b); }
  Rgb operator+(Rgb o) const { return {r + o.r, g + o.g, b + o.b}; }
  Rgb operator-(Rgb o) const { return {r - o.r, g - o.g, b - o.b}; }
  Rgb operator*(Rgb o) const { return {r * o.r, g * o.g, b * o.b}; }
  Rgb operator/(Rgb o) const { return {r / o.r, g / o.g, b / o.b}; }
  Rgb operator*(float s) const { return {r * s, g * s, b * s}; }
  Rgb operator/(float s) const { return *this * (1.0f / s); }
  Rgb& operator+=(Rgb o) { r += o.r; g += o.g; b += o.b; return *this; }
  Rgb& operator*=(Rgb o) { r *= o.r; g *= o.g; b *= o.b; return *this; }
  Rgb& operator*=(float s) { r *= s; g *= s; b *= s; return *this; }
  bool is_black() const { return r == 0.0f && g == 0.0f && b == 0.0f; }
};
inline Rgb operator*(float s, Rgb c) { return c * s; }
inline float luminance(Rgb c) { return 0.212671f * c.r + 0.715160f * c.g + 0.072169f * c.b; }
inline float max_component(Rgb c) { return std::max(c.r, std::max(c.g, c.b)); }
inline float average(Rgb c) { return (c.r + c.g + c.b) * (1.0f / 3.0f); }
inline bool is_finite(Rgb c) { return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b); }

}  // namespace gdvr
