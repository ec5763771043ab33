// The first hit of a camera ray: where a base or offset path of G-PT starts.
// Traced once and handed to the path code, so that a ray shared by several
// paths (a pixel's base path and its neighbours' offsets into that pixel,
// CameraHitCache) is intersected and shaded only once.
#pragma once

#include "core/render/frame_scene.h"
#include "core/render/path_tracer.h"

namespace gdvr {

struct CameraHit {
  Ray ray;
  bool hit = false;
  SurfaceInteraction si;  // valid when `hit`
};

// Intersects `ray` with the scene (one ray, counted) into `*out`, written in
// place: copying a just-written hit stalls on store-to-load forwarding.
inline void trace_camera_hit(const FrameScene& scene, const Ray& ray, PathCounters& counters, CameraHit* out) {
  out->ray = ray;
  ++counters.rays;
  out->hit = scene.intersect_camera_ray(ray, &out->si);
}

inline CameraHit trace_camera_hit(const FrameScene& scene, const Ray& ray, PathCounters& counters) {
  CameraHit h;
  trace_camera_hit(scene, ray, counters, &h);
  return h;
}

}  // namespace gdvr
