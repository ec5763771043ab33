// Options of the spatial gradient-domain path tracer (Kettunen et al. 2015;
// docs/gpt.md): which shift mapping builds the offsets, whether the
// offsets are built from the cached base path only with probability q
// (docs/gpt.md, "Cached-path Russian roulette"), how vertices are classified,
// and how the frame is reconstructed.
// Validated once before a frame; printable for logs.
#pragma once

#include <string>

#include "core/recon/recon_settings.h"
#include "core/util/enum_names.h"
#include "core/util/status.h"

namespace gdvr {

enum class ShiftMapping {
  kReplay,     // random replay in primary sample space (§3.2): the test oracle
  kReconnect,  // reconnection with half-vector copy (§3.1): the G-PT default
  kHybrid,     // replay until the first diffuse-diffuse pair, then reconnect
};

// The spellings of job files and flags ("shift", --shift).
inline constexpr EnumNames<ShiftMapping, 3> kShiftMappingNames = {{{ShiftMapping::kReplay, "replay"},
                                                                   {ShiftMapping::kReconnect, "reconnect"},
                                                                   {ShiftMapping::kHybrid, "hybrid"}}};
inline const char* shift_mapping_name(ShiftMapping m) { return enum_name(kShiftMappingNames, m); }
inline Expected<ShiftMapping> parse_shift_mapping(const std::string& name) {
  return parse_enum_name(kShiftMappingNames, name, "shift");
}

// The G-PT paper's choice and every job's default.
inline constexpr ShiftMapping kDefaultShiftMapping = ShiftMapping::kReconnect;

struct GptSettings {
  ShiftMapping shift = kDefaultShiftMapping;
  // Cached-path shifting with Russian roulette (§3.3): build the offsets with
  // probability q = max(min(1, lum f(x)), q_min) and divide by q.
  bool cached_rr = true;
  float cached_rr_min_q = 0.1f;
  // Sample s of every pixel goes through the same sub-pixel position, drawn
  // per (seed, frame, s): the offset of pixel p into its neighbour j then
  // starts with j's own base camera ray, and the first hit is traced once
  // for both (CameraHitCache). Each pixel's estimate is as before (the
  // position is uniform in the pixel); what changes is that neighbouring
  // pixels' anti-aliasing errors are correlated. Off: independent positions
  // per pixel, as PT's (the base paths are then exactly PT's paths for the
  // same seed; with it on, only their camera rays differ).
  bool shared_jitter = true;
  // The primal the reconstruction gets: false, the base path's plain estimate
  // (PT's estimator); true, the MIS-weighted pair primal (Kettunen et al.
  // 2015): for each neighbour j, the pair's two generations' weighted
  // estimates of I(p), averaged over the neighbours (GradientFilm). Under
  // cached-path RR it is kept unbiased with 1/q terms.
  bool pair_primal = false;
  // A vertex whose BSDF roughness exceeds this is "diffuse" (reconnectable);
  // otherwise glossy/specular (half-vector copy). 0.001 in the G-PT release.
  float diffuse_roughness = 0.001f;
  // Tiny epsilon in the MIS denominator w = 1 / (1 + r + eps) (1e-14 in the release).
  double mis_epsilon = 1e-14;
  // How the job turns the sampled buffers into the final image.
  ReconSettings recon;

  // The defaults per shift: cached RR is on for reconnect (and hybrid), off for replay.
  static GptSettings defaults_for(ShiftMapping shift);
  Status validate() const;
  std::string to_string() const;
};

}  // namespace gdvr
