#include "core/job/job_validation.h"

#include <cmath>
#include <cstdio>

#include "core/io/image_io.h"
#include "core/util/echo_text.h"

namespace gdvr {
namespace {

Status field_error(const std::string& field, const std::string& problem) {
  return invalid_argument("job." + field + ": " + problem);
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", v);
  return buf;
}

Status validate_reconstruction(const ReconstructionSpec& r) {
  const std::vector<double>& w = r.term_weights;
  if (!w.empty()) {
    if (w.size() != size_t(kTermCount))
      return field_error("reconstruction.term_weights", "must be an array of " + std::to_string(kTermCount) + " numbers");
    for (size_t k = 0; k < w.size(); ++k)
      if (!(w[k] >= 0) || !std::isfinite(w[k]) || w[k] > kMaxTermWeight)
        return field_error("reconstruction.term_weights[" + std::to_string(k) + "]", "must be in [0, " + number_text(kMaxTermWeight) + "]");
    if (w[0] == 0) return field_error("reconstruction.term_weights[0]", "the primal's weight must be positive");
  }
  if (!(r.alpha >= 0) || !std::isfinite(r.alpha)) return field_error("reconstruction.alpha", "must be >= 0");
  if (r.window < 1 || r.window > kMaxWindowFrames)
    return field_error("reconstruction.window", "must be in [1, " + std::to_string(kMaxWindowFrames) + "]");
  if (r.tile_size != 0 && (r.tile_size < kMinReconTileSize || r.tile_size > kMaxJobResolution))
    return field_error("reconstruction.tile_size", "must be 0 (no tiling) or in [" + std::to_string(kMinReconTileSize) +
                                                       ", " + std::to_string(kMaxJobResolution) + "]");
  return Status::Ok();
}

Status validate_direct_light(const DirectLightSpec& d) {
  const std::string range = "must be in [0, " + std::to_string(kMaxDirectStrata) + "]";
  if (d.strata && (*d.strata < 0 || *d.strata > kMaxDirectStrata))
    return field_error("direct_light.strata",
                       range + " (0: from the paths' own samples; leave it out for the integrator's default)");
  if (d.edge_strata && (*d.edge_strata < 0 || *d.edge_strata > kMaxDirectStrata))
    return field_error("direct_light.edge_strata", range + " (leave it out for the integrator's default)");
  return Status::Ok();
}

}  // namespace

Status validate(const JobSpec& job) {
  if (job.scene.empty()) return field_error("scene", "missing");
  if (!(job.fps > 0) || !(job.fps <= kMaxJobFps)) return field_error("fps", "must be in (0, " + number_text(kMaxJobFps) + "]");
  const std::string resolution = "must be in [0, " + std::to_string(kMaxJobResolution) + "] (0: the scene's)";
  if (job.width < 0 || job.width > kMaxJobResolution) return field_error("width", resolution);
  if (job.height < 0 || job.height > kMaxJobResolution) return field_error("height", resolution);
  if (job.spp < 0 || job.spp > kMaxJobSpp)
    return field_error("spp", "must be in [0, " + std::to_string(kMaxJobSpp) + "] (0: the scene's)");
  if (!(job.time_budget_s >= 0) || !std::isfinite(job.time_budget_s)) return field_error("time_budget_s", "must be >= 0");
  {
    // A range over the frame limit keeps its RESOURCE_EXHAUSTED code.
    auto frames = parse_frame_range(job.frames);
    if (!frames.ok()) return Status(frames.status().code(), "job.frames: " + frames.status().message());
  }
  GDVR_RETURN_IF_ERROR(validate_reconstruction(job.reconstruction));
  if (job.reconstruction.data_term == DataTerm::kDenoised &&
      (job.integrator != Integrator::kTgpt ||
       (job.reconstruction.method != ReconMethod::kL1 && job.reconstruction.method != ReconMethod::kL2)))
    return field_error("reconstruction.data_term",
                       "'denoised' applies to integrator tgpt with method l1 or l2 (the screened Poisson solves)");
  GDVR_RETURN_IF_ERROR(validate_direct_light(job.direct_light));
  const std::string& codec = job.outputs.video_codec;
  if (codec != "h264" && codec != "prores" && codec != "ffv1" && codec != "none")
    return field_error("outputs.video_codec", "must be h264, prores, ffv1 or none, not '" + echo_text(codec) + "'");
  if (const std::string& c = job.outputs.exr_compression; c != "auto" && !parse_exr_compression(c).ok())
    return field_error("outputs.exr_compression", "must be auto, zip, zips, rle, piz or none, not '" + echo_text(c) + "'");
  return Status::Ok();
}

}  // namespace gdvr
