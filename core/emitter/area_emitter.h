// Area lights: one-sided emission from a shape's surface. A sphere light is
// sampled within the cone of directions it subtends (uniformly by area from
// inside it); a triangle mesh light picks a triangle by area, then a point
// uniformly on it. FrameScene keeps each emitting shape's world-space
// geometry (centre and radius, or EmitterTriangles) and calls these.
#pragma once

#include <cstddef>
#include <vector>

#include "core/emitter/emitter_sample.h"
#include "core/math/distribution.h"

namespace gdvr {

// A mesh light's triangle in world space. `n` is what FrameScene's
// interaction() shades a hit on it with (flip_normals applied), so that a
// sampled point and a hit there agree bit for bit; where the mesh's vertex
// normals are not the face normal (`face_normal` false) the caller
// interpolates them at the sample instead. One record instead of the index
// buffer, three vertices and two per-triangle tables.
struct EmitterTriangle {
  Vec3f p0, p1, p2;
  Vec3f n;
  bool face_normal = true;
};

// A point sampled on an area light: `n` its emitting side's normal; `pdf` the
// solid-angle density where the point was sampled by solid angle, or
// `area_measure` where it was sampled uniformly by area (area_emitter_sample
// converts).
struct AreaEmitterPoint {
  Vec3f p, n;
  float pdf = 0;
  bool area_measure = false;
};

AreaEmitterPoint sample_sphere_emitter_point(Vec3f center, float radius, bool flip_normals, Vec3f ref_p, Vec2f u);
// Also which triangle and where on it (barycentrics b1, b2), for a caller
// that interpolates vertex normals there.
AreaEmitterPoint sample_triangle_emitter_point(const Distribution1D& triangle_areas,
                                               const std::vector<EmitterTriangle>& triangles, Vec2f u,
                                               size_t* triangle, Vec2f* b);

// The direction sample from `ref_p` towards `pt` on a light of total area
// `area` and radiance `radiance`. `es` arrives with its emitter index set;
// `select_pdf` is the emitter selection's.
EmitterSample area_emitter_sample(Vec3f ref_p, const AreaEmitterPoint& pt, float area, Rgb radiance, float select_pdf,
                                  EmitterSample es);

// Solid-angle densities (without emitter selection) of having sampled
// `hit_p`, whose shading normal is `hit_n`, from `ref_p`: a mesh light's,
// and a sphere light's, formed exactly as the samples form them so that MIS
// sees equal pdfs.
float mesh_emitter_pdf(float area, Vec3f ref_p, Vec3f hit_p, Vec3f hit_n);
float sphere_emitter_pdf(Vec3f center, float radius, float area, Vec3f ref_p, Vec3f hit_p, Vec3f hit_n);

}  // namespace gdvr
