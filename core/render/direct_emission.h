// Emission seen directly from the camera ("very direct" light, docs/gpt.md,
// "Direct light"),
// estimated apart from the paths with k×k stratified, jittered camera samples
// per pixel, more of them where an emitter's edge crosses the pixel.
//
// Why a pass of its own: the gradient-domain integrators keep this light out
// of the solve and add it afterwards, so its noise reaches the output
// unfiltered. It is not noise-free in practice at low sample counts: the
// anti-aliased edge of a small bright emitter gets one hit or miss per camera
// sample (a 0/1 estimate of the covered fraction), and on the Cornell box the
// light's ~1 % of pixels carried over 90 % of the per-pixel relMSE of a T-GPT
// frame at 8 spp (docs/gpt.md). Stratified jitter turns the error of a pixel
// crossed by an edge from O(1/N) into O(1/N^1.5) in the ray count N, and the
// pass costs only primary rays (k² per pixel), far less than the paths.
//
// The estimate is unbiased for any k (each stratum is sampled uniformly), and
// the choice of k per pixel depends only on deterministic probe rays, never on
// the estimate's own random numbers, so the adaptive pass is unbiased too. The
// jitter depends on (seed, stream, pixel, stratum) only, so it is
// deterministic across thread counts; callers that pass the same stream for
// every frame get the same jitter pattern in each frame, which keeps the error
// of static emitter edges the same from frame to frame (no flicker).
#pragma once

#include <atomic>
#include <cstdint>
#include <vector>

#include "core/image/image.h"
#include "core/render/frame_scene.h"
#include "core/render/path_tracer.h"
#include "core/render/perspective_camera.h"
#include "core/util/status.h"

namespace gdvr {

struct DirectEmissionSettings {
  // k: k×k samples per pixel; 0 = no separate pass (the integrator takes the
  // direct light from its paths' own camera samples).
  int strata = 4;
  // k in pixels an emitter edge crosses, found by deterministic probes on a
  // half-pixel grid (~4 rays per pixel; only when edge_strata > strata).
  // With probes, pixels whose probes all see the same emission take a single
  // sample, and `strata` applies where the emission varies smoothly.
  int edge_strata = 16;
  // Pixels whose probes all agree (one sample would do) take no ray of their
  // own: the caller's paths, which see emitters at their camera vertex anyway,
  // estimate them (DirectEmissionResult::from_paths). Only for callers that
  // keep that estimate apart (the gradient-domain integrators); PT's paths
  // leave emission out when the pass runs.
  bool uniform_from_paths = false;
  // Probe by the area emitters' projected bounds: pixels outside them see no
  // emission but the environment's, if any. Without an environment they are
  // 0 without a probe or a sample; with one, they take their four corner
  // probes first and the other five only where those differ.
  bool use_emitter_bounds = true;

  bool enabled() const { return strata > 0; }
  Status validate() const;  // 0 <= strata <= edge_strata <= 64
};

// What the integrators use unless the job says otherwise: pt keeps Mitsuba's
// estimator (the paths' own samples; what MitsubaAgreementTest compares),
// gpt and tgpt, which add the direct light after the solve, the pass.
inline DirectEmissionSettings default_direct_emission(bool gradient_domain) {
  return gradient_domain ? DirectEmissionSettings{4, 16, true} : DirectEmissionSettings{0, 0, false};
}

struct DirectEmissionResult {
  Image direct;                  // RGB mean emission over the pixel
  uint64_t rays = 0;             // camera rays traced (k² per pixel)
  uint64_t invalid_samples = 0;  // non-finite emission dropped (counted, never silent)
  uint64_t edge_pixels = 0;      // pixels sampled with edge_strata
  uint64_t culled_pixels = 0;    // pixels that can see no emission (use_emitter_bounds): 0, no ray
  // Per pixel (row-major), 1 where the pass left the estimate to the caller's
  // paths (settings.uniform_from_paths); empty when it left none.
  std::vector<uint8_t> from_paths;
};

// The direct light of a frame: the pass's estimate, and the paths' (the mean
// first-hit emission of the caller's own camera samples; the mean of two
// equal-sized sets of paths when `paths_b` is given) where the pass left the
// pixel to them. Unbiased: which pixels those are depends only on the
// deterministic probes, never on the paths' random numbers.
Image merge_direct_estimates(DirectEmissionResult&& pass, const Image& paths, const Image* paths_b = nullptr);

// The stream the gradient-domain integrators pass for every frame (a fixed
// jitter pattern; the pass's sample indices never meet the paths' own).
constexpr uint32_t kDirectEmissionStream = 0;

// Honours path.hide_emitters (all black). Returns kCancelled when *cancel is
// set before the last tile.
Expected<DirectEmissionResult> render_direct_emission(const FrameScene& scene, const PerspectiveCamera& camera,
                                                      int width, int height, const DirectEmissionSettings& settings,
                                                      uint64_t seed, uint32_t stream, const PathTracerSettings& path,
                                                      int threads, const std::atomic<bool>* cancel);

// The first-hit emission of one camera ray, exactly as trace_path counts it
// at depth 0 (environment on a miss, the area emitter of the hit shape).
Rgb first_hit_emission(const FrameScene& scene, const Ray& camera_ray);

}  // namespace gdvr
