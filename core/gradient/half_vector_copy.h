// Half-vector copy of a glossy/specular bounce (Kettunen et al. 2015 §5.2,
// after Lehtinen et al. 2013): keep the base's half vector fixed in the local
// shading frame and reflect or refract the offset's outgoing direction about it.
// Jacobians follow from dω_h/dω_i (Walter et al. 2007, Eqs. 14 and 16):
//   reflection  |J| = |ω'_i·h| / |ω_i·h|
//   refraction  |J| = (|H'|² / |H|²) · |ω_i·h| / |ω'_i·h|,   H = ω_o + η ω_i,
// where ω_i is the sampled direction and η = η_i/η_o (BsdfSample::eta).
#pragma once

#include <cmath>

#include "core/math/vec.h"

namespace gdvr {

struct HalfVectorCopy {
  Vec3f wi;            // the offset's new direction (local frame)
  float jacobian = 0;  // dω'_i / dω_i
};

// False where the copy does not exist: degenerate half vector, microfacet
// facing away, total internal reflection, index-matched refraction, or an
// offset that would switch between reflection and transmission (not invertible).
inline bool copy_half_vector(Vec3f wo_b, Vec3f wi_b, float eta_b, Vec3f wo_o, HalfVectorCopy* out) {
  const bool reflection = wo_b.z * wi_b.z > 0;
  if (reflection) {
    Vec3f h = wo_b + wi_b;
    float l2 = length_squared(h);
    if (!(l2 > 1e-12f)) return false;
    h = h / std::sqrt(l2);
    float cos_o = dot(wo_o, h), cos_b = dot(wi_b, h);
    if (!(cos_o > 1e-7f) || !(cos_b > 1e-7f)) return false;
    out->wi = 2.0f * cos_o * h - wo_o;
    if (!(out->wi.z * wo_o.z > 0)) return false;
    out->jacobian = cos_o / cos_b;  // ω'_i·h = ω'_o·h for a reflection
    return std::isfinite(out->jacobian);
  }
  if (std::abs(eta_b - 1.0f) < 1e-4f) return false;  // index-matched: no half vector
  if (!(wo_o.z * wo_b.z > 0)) return false;          // offset on the other side: another η
  Vec3f big_h = wo_b + wi_b * eta_b;
  float l2 = length_squared(big_h);
  if (!(l2 > 1e-12f)) return false;
  Vec3f h = big_h / std::sqrt(l2);
  const float c = dot(wo_o, h), inv_eta = 1.0f / eta_b;
  const float sin2_t = inv_eta * inv_eta * (1.0f - c * c);
  if (!(sin2_t < 1.0f)) return false;  // total internal reflection
  float cos_t = std::sqrt(1.0f - sin2_t);
  if (c > 0) cos_t = -cos_t;
  Vec3f wi = h * (c * inv_eta + cos_t) - wo_o * inv_eta;  // Mitsuba's refract() about h
  if (!(wi.z * wo_o.z < 0)) return false;
  Vec3f big_h_o = wo_o + wi * eta_b;
  float dot_b = std::abs(dot(wi_b, h)), dot_o = std::abs(dot(wi, h));
  if (!(dot_o > 1e-7f)) return false;
  out->wi = wi;
  out->jacobian = length_squared(big_h_o) / l2 * dot_b / dot_o;
  return std::isfinite(out->jacobian) && out->jacobian > 0;
}

}  // namespace gdvr
