// Fresnel equations and reflect/refract helpers in the local shading frame,
// with Mitsuba 3's conventions (include/mitsuba/render/fresnel.h): eta is the
// relative IOR (interior / exterior), cos_theta_i < 0 means arriving from inside.
#pragma once

#include <cmath>

#include "core/math/vec.h"

namespace gdvr {

struct FresnelResult {
  float f = 1;            // unpolarised reflectance
  float cos_theta_t = 0;  // signed cosine of the transmitted direction (opposite side of cos_theta_i)
  float eta_it = 1;       // relative IOR in the direction of travel
  float eta_ti = 1;       // 1 / eta_it: the scale of the tangential part of the refracted direction
};

// Dielectric Fresnel (Mitsuba `fresnel`). Index-matched interfaces reflect
// nothing; grazing incidence and total internal reflection reflect everything.
inline FresnelResult fresnel_dielectric(float cos_theta_i, float eta) {
  FresnelResult r;
  bool outside = cos_theta_i >= 0.0f;
  float rcp_eta = 1.0f / eta;
  r.eta_it = outside ? eta : rcp_eta;
  r.eta_ti = outside ? rcp_eta : eta;
  // Snell's law: squared cosine of the transmitted angle (negative under TIR).
  float cos_theta_t_sqr = 1.0f - (1.0f - cos_theta_i * cos_theta_i) * (r.eta_ti * r.eta_ti);
  float ci = std::abs(cos_theta_i);
  float ct = safe_sqrt(cos_theta_t_sqr);
  if (eta == 1.0f) {
    r.f = 0.0f;
  } else if (ci == 0.0f) {
    r.f = 1.0f;
  } else {
    float a_s = (ci - r.eta_it * ct) / (ci + r.eta_it * ct);
    float a_p = (ct - r.eta_it * ci) / (ct + r.eta_it * ci);
    r.f = 0.5f * (a_s * a_s + a_p * a_p);
  }
  r.cos_theta_t = outside ? -ct : ct;
  return r;
}

// Conductor Fresnel for a complex IOR eta + i k, light arriving from outside
// (Mitsuba `fresnel_conductor`, after Moeller, "Optics", 1988). Per channel.
inline float fresnel_conductor(float cos_theta_i, float eta, float k) {
  float c2 = cos_theta_i * cos_theta_i, s2 = 1.0f - c2, s4 = s2 * s2;
  float temp1 = eta * eta - k * k - s2;
  float a2pb2 = safe_sqrt(temp1 * temp1 + 4.0f * k * k * eta * eta);
  float a = safe_sqrt(0.5f * (a2pb2 + temp1));
  float term1 = a2pb2 + c2, term2 = 2.0f * cos_theta_i * a;
  float r_s = (term1 - term2) / (term1 + term2);
  float term3 = a2pb2 * c2 + s4, term4 = term2 * s2;
  float r_p = r_s * (term3 - term4) / (term3 + term4);
  return 0.5f * (r_s + r_p);
}

inline Rgb fresnel_conductor(float cos_theta_i, Rgb eta, Rgb k) {
  return {fresnel_conductor(cos_theta_i, eta.r, k.r), fresnel_conductor(cos_theta_i, eta.g, k.g),
          fresnel_conductor(cos_theta_i, eta.b, k.b)};
}

// Diffuse Fresnel reflectance Fdr (Mitsuba `fresnel_diffuse_reflectance`): the
// fits of Egan & Hilgeman 1973 for eta < 1 and d'Eon & Irving 2011 otherwise.
inline float fresnel_diffuse_reflectance(float eta) {
  if (eta < 1.0f)
    return -1.4399f * (eta * eta) + 0.7099f * eta + 0.6681f + 0.0636f / eta;
  float i1 = 1.0f / eta, i2 = i1 * i1, i3 = i2 * i1, i4 = i3 * i1, i5 = i4 * i1;
  return 0.919317f - 3.4793f * i1 + 6.75335f * i2 - 7.80989f * i3 + 4.98554f * i4 - 1.36881f * i5;
}

// Mirror about the local normal (0, 0, 1).
inline Vec3f reflect_local(Vec3f w) { return {-w.x, -w.y, w.z}; }
// Refraction about the local normal, cos_theta_t and eta_ti from fresnel_dielectric().
inline Vec3f refract_local(Vec3f w, float cos_theta_t, float eta_ti) {
  return {-eta_ti * w.x, -eta_ti * w.y, cos_theta_t};
}
// Refraction about a microfacet normal m.
inline Vec3f refract_about(Vec3f w, Vec3f m, float cos_theta_t, float eta_ti) {
  return m * (dot(w, m) * eta_ti + cos_theta_t) - w * eta_ti;
}

}  // namespace gdvr
