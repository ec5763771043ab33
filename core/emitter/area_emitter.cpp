#include "core/emitter/area_emitter.h"

#include <cmath>

#include "core/math/frame.h"
#include "core/math/sampling.h"
#include "core/math/sincos.h"

namespace gdvr {
namespace {

// Outside the sphere (by a margin against rounding): the cone sampling applies.
bool outside_sphere(float dc2, float r2) { return dc2 > r2 * (1.0f + 1e-5f); }

}  // namespace

AreaEmitterPoint sample_sphere_emitter_point(Vec3f center, float radius, bool flip_normals, Vec3f ref_p, Vec2f u) {
  AreaEmitterPoint pt;
  Vec3f dc = center - ref_p;
  float dc2 = length_squared(dc);
  float r2 = radius * radius;
  if (outside_sphere(dc2, r2)) {
    // Sample the cone of directions the sphere subtends and place the point
    // on the sphere from the cone angles (pbrt-v4's construction;
    // sphere_point_in_cone). Intersecting the sampled ray with the sphere
    // instead cancels catastrophically in float for a light 1e-3 of its
    // distance across and put points on the far side (back-facing: zero
    // radiance, a -0.2 % bias; docs/stability.md). The pdf is formed in
    // double from (radius, distance) alone, exactly as sphere_emitter_pdf
    // forms it, so that MIS sees equal pdfs; it is off the sample's
    // dependency chain.
    const SphereConePoint c = sphere_point_in_cone(r2 / dc2, u.y);
    // The azimuth needs no care: an error of 1e-7 rad moves the point by 1e-7 radii.
    const SinCos phi = sincos_turns(u.x);
    const Frame frame(dc * (1.0f / std::sqrt(dc2)));  // z towards the centre
    // Unit up to rounding (an orthonormal frame and a unit vector): no normalisation.
    pt.n = frame.to_world(Vec3f(-c.sin_c * phi.cos, -c.sin_c * phi.sin, -c.cos_c));
    pt.p = center + pt.n * radius;
    pt.pdf = sphere_cone_pdf(double(dc2), double(radius) * double(radius));
  } else {
    // Inside (or on) the sphere: uniform area sampling.
    pt.n = square_to_uniform_sphere(u);
    pt.p = center + pt.n * radius;
    pt.area_measure = true;
  }
  if (flip_normals) pt.n = -pt.n;
  return pt;
}

AreaEmitterPoint sample_triangle_emitter_point(const Distribution1D& triangle_areas,
                                               const std::vector<EmitterTriangle>& triangles, Vec2f u,
                                               size_t* triangle, Vec2f* b) {
  float u_tri;
  const size_t t = triangle_areas.sample(u.x, &u_tri);
  const EmitterTriangle& tri = triangles[t];
  *b = square_to_uniform_triangle({u_tri, u.y});
  *triangle = t;
  AreaEmitterPoint pt;
  pt.p = tri.p0 * (1.0f - b->x - b->y) + tri.p1 * b->x + tri.p2 * b->y;
  pt.n = tri.n;
  pt.area_measure = true;
  return pt;
}

EmitterSample area_emitter_sample(Vec3f ref_p, const AreaEmitterPoint& pt, float area, Rgb radiance, float select_pdf,
                                  EmitterSample es) {
  Vec3f d = pt.p - ref_p;
  float dist2 = length_squared(d);
  float dist = std::sqrt(dist2);
  float pdf_solid_angle = pt.pdf;
  if (pt.area_measure) {
    // Area to solid angle: dist^2 / (area cos_l) with cos_l = |d.n| / dist,
    // grouped so that no extra division or overflow enters.
    float abs_dn = std::abs(dot(d, pt.n));
    pdf_solid_angle = abs_dn > 0 ? dist2 * (dist / (area * abs_dn)) : 0.0f;
  }
  if (!(dist > 0) || !(pdf_solid_angle > 0) || !std::isfinite(pdf_solid_angle)) return es;
  es.d = d * (1.0f / dist);
  es.dist = dist;
  es.pdf = pdf_solid_angle * select_pdf;
  // One-sided: emits only on the side its normal faces.
  if (dot(pt.n, es.d) < 0) es.weight = radiance / es.pdf;
  return es;
}

float mesh_emitter_pdf(float area, Vec3f ref_p, Vec3f hit_p, Vec3f hit_n) {
  Vec3f d = hit_p - ref_p;
  float dist2 = length_squared(d);
  float cos_l = std::abs(dot(d, hit_n)) / std::sqrt(dist2);
  return cos_l > 0 ? dist2 / (area * cos_l) : 0.0f;
}

float sphere_emitter_pdf(Vec3f center, float radius, float area, Vec3f ref_p, Vec3f hit_p, Vec3f hit_n) {
  Vec3f dc = center - ref_p;
  float dc2 = length_squared(dc), r2 = radius * radius;
  if (outside_sphere(dc2, r2)) return sphere_cone_pdf(double(dc2), double(radius) * double(radius));
  return mesh_emitter_pdf(area, ref_p, hit_p, hit_n);
}

}  // namespace gdvr
