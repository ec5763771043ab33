// Environment emitters: a constant radiance from every direction, or a
// lat-long environment map (Mitsuba's `envmap`) sampled by its luminance.
// FrameScene keeps one EnvmapTables per envmap emitter and calls these for
// next-event estimation, for rays that escape the scene and for MIS.
#pragma once

#include <memory>

#include "core/emitter/emitter.h"
#include "core/emitter/emitter_sample.h"
#include "core/math/distribution.h"

namespace gdvr {

// What sampling an envmap needs beyond the Emitter: its sampling density
// (which depends on the image alone, so a rotation keeps it) and the
// world-to-map rotation, inverted once.
struct EnvmapTables {
  std::shared_ptr<const Image> image;
  Distribution2D distribution;
  Transform to_local;  // world -> the envmap's frame (to_world⁻¹)
};

// The density environment samples are drawn from (envmap_distribution in
// environment_emitter.cpp says how it is laid out).
Distribution2D envmap_distribution(const Image& img);

// Next-event samples of a direction towards the environment. `es` arrives
// with its emitter index set; `select_pdf` is the emitter selection's.
EmitterSample sample_constant_emitter(const Emitter& em, Vec2f u, float select_pdf, EmitterSample es);
EmitterSample sample_envmap_emitter(const Emitter& em, const EnvmapTables& env, Vec2f u, float select_pdf,
                                    EmitterSample es);

// Radiance of the envmap along world direction `d`.
Rgb eval_envmap(const Emitter& em, const EnvmapTables& env, Vec3f d);
// Solid-angle density (without emitter selection) of sampling world
// direction `d` from the envmap.
float envmap_pdf(const EnvmapTables& env, Vec3f d);

// Both at once: one direction-to-uv conversion (its atan2 and acos were 4 %
// of PT on matpreview when radiance and pdf each did it). The pdf is without
// emitter selection.
struct EnvmapLookup {
  Rgb radiance;
  float pdf = 0;
};
EnvmapLookup envmap_along(const Emitter& em, const EnvmapTables& env, Vec3f d);

// Starts loading the alias slots and texels that sample_envmap_emitter(u)
// will read (tables too big for the cache; see FrameScene::prefetch_emitter_sample).
void prefetch_envmap_sample(const EnvmapTables& env, Vec2f u);

}  // namespace gdvr
