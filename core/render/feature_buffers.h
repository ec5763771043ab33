// Feature buffers: per pixel, the albedo, shading normal and depth of what the
// camera sees, the auxiliary images a denoiser guided by features wants
// (Intel Open Image Denoise's `albedo` and `normal`) and a compositor's depth.
//
// What a camera sample records. Delta surfaces (smooth conductors, smooth and
// thin dielectrics) are followed to the first surface that is not one, as
// OIDN's docs recommend, so a mirror or a pane of glass shows the albedo and
// normal of what it reflects or lets through:
//   albedo: bsdf_albedo() of that surface (core/bsdf/bsdf_albedo.h); the
//           emitted radiance clamped to [0, 1] where it is an area emitter or
//           the ray escaped to the environment (0 without one);
//   normal: its world-space unit shading normal; 0 where the ray escaped
//           (OIDN's "no surface");
//   depth:  the distance from the camera to the first surface the camera ray
//           meets (delta or not: a compositor's Z is the visible surface),
//           kMissDepth where it meets none.
// Where a delta surface both reflects and transmits (glass), the sample
// splits into both branches weighted by their Fresnel probabilities and each
// branch's tint: the pixel gets OIDN's "Fresnel blend of the reflected and
// transmitted albedos" (and normals) without noise, up to
// FeatureBufferSettings::max_branches branches; past that the likelier branch
// goes on alone.
//
// What a pixel holds: the mean of its k×k jittered samples (a box filter, as
// the beauty image's) for albedo and normal, so a normal is unit length where
// the pixel sees one flat surface and shorter across silhouettes (OIDN
// accepts any length); for depth the smallest sample distance, the nearest
// surface in the pixel (a mean would invent depths between a foreground edge
// and the background).
//
// Deterministic: the jitter depends on (seed, pixel, stratum) only, not on the
// frame, thread count or tile order, so static content gives the same
// features in every frame. The pass traces only camera rays and their delta
// chains: about k² rays per pixel on scenes without glass or mirrors.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"
#include "core/util/status.h"

namespace gdvr {

// The depth of a pixel that sees nothing: far past any scene, but finite, so
// that every stage that treats a non-finite value as a corrupted buffer (and
// zeroes it) leaves it alone, and sums over a depth image stay finite.
constexpr float kMissDepth = 1e10f;

struct FeatureBufferSettings {
  int strata = 4;  // k: k×k jittered samples per pixel
  // Delta vertices a sample follows before it takes the last one's
  // bsdf_albedo() (mirrors facing each other, light trapped in glass).
  int max_specular_depth = 8;
  // Branches a camera sample may split into at glass (see above).
  int max_branches = 8;

  Status validate() const;  // 1 <= strata <= 64, max_specular_depth >= 0, max_branches >= 1
};

struct FeatureBuffers {
  Image albedo;  // RGB in [0, 1]
  Image normal;  // world-space XYZ
  Image depth;   // one channel
  uint64_t rays = 0;
  double seconds = 0;
};

// The pattern for a frame of `spp` samples per pixel (the pass size under a
// time budget): k = floor(sqrt(spp)) clamped to [2, 4]. The pass then costs a
// fixed share of the render, as a path sample traces several rays and a
// feature sample about one: 2×2 for the few samples of a preview or a time
// budget's passes (where a 4×4 pass would cost more than the sampling it
// guides: the report's denoised baselines), 4×4 from 16 spp.
FeatureBufferSettings feature_buffer_settings_for(int spp);

// What one camera ray records (the pixel's values before averaging).
struct FeatureSample {
  Rgb albedo;
  Vec3f normal;
  float depth = kMissDepth;
  uint32_t rays = 0;
};

// Traces camera rays' features, one at a time; one per thread (it keeps the
// branches waiting at glass between calls rather than making room per ray).
class FeatureTracer {
 public:
  // `hide_emitters`: emitters and the environment seen directly from the
  // camera count as the image shows them (black; an area emitter's own BSDF
  // albedo), not through a delta surface, as in the path tracer.
  FeatureTracer(const FrameScene& scene, const FeatureBufferSettings& settings, bool hide_emitters);
  FeatureSample trace(const Ray& camera_ray);

 private:
  // One path of a camera sample through delta surfaces, with what it still
  // contributes: the delta lobes' tints (albedo) and probabilities (normal).
  struct Branch {
    Ray ray;
    Rgb tint;
    float weight;
    int depth;  // delta vertices behind it
  };
  const FrameScene& scene_;
  FeatureBufferSettings settings_;
  bool hide_emitters_;
  std::vector<Branch> waiting_;
};

// The frame's feature buffers at frame.width × frame.height with frame.seed,
// frame.threads, frame.tile_size and frame.path.hide_emitters. Returns
// kCancelled when *cancel is set before the last tile.
Expected<FeatureBuffers> render_feature_buffers(const FrameScene& scene, const FrameRenderSettings& frame,
                                                const FeatureBufferSettings& settings,
                                                const std::atomic<bool>* cancel);

// The EXR layers the buffers become, named as compositors expect: albedo.R/G/B,
// N.X/Y/Z and the bare Z channel (core/io/image_io.h writes a one-channel
// layer named as its channel as that bare channel).
inline const char* const kAlbedoLayer = "albedo";
inline const char* const kNormalLayer = "N";
inline const char* const kDepthLayer = "Z";
const std::vector<std::string>& feature_layer_names();
void add_feature_layers(FeatureBuffers&& buffers, LayeredImage* out);
// Appends the feature layers `from` has to `to` (a finalize stage that builds
// its output layer by layer).
void copy_feature_layers(const LayeredImage& from, LayeredImage* to);

}  // namespace gdvr
