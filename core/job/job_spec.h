// The job: what to render and how. Its JSON form is the job file of
// gdvr-render and the CLI, and the protobuf JSON form of gdvr.v1.JobSpec
// (field names are the proto field names, snake_case), so one schema serves
// everywhere. Unknown JSON fields are errors.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/gradient/gpt_settings.h"
#include "core/job/integrators/integrator.h"
#include "core/job/job_defaults.h"
#include "core/recon/recon_settings.h"
#include "core/scene/animation.h"
#include "core/temporal/tgpt_settings.h"
#include "core/util/status.h"

namespace gdvr {

struct ReconstructionSpec {
  ReconMethod method = kDefaultJobReconMethod;
  double alpha = kDefaultReconAlpha;
  int window = kDefaultWindowFrames;  // frames in the temporal sliding window
  // T-GPT's window solve by tiles of at most tile_size pixels a side for
  // larger frames (docs/reconstruction.md, "Tiled solve"); 0: never tiled.
  int tile_size = kDefaultReconTileSize;
  // Extra weight per term (primal, dx, dy, dt, dxdt, dydt); empty = all 1.
  // 0 drops a term (e.g. {1, 1, 1, 0, 0, 0}: a window without temporal terms).
  std::vector<double> term_weights;
  // The gradient-domain integrators' output clamped at 0 (add_direct_clamped
  // in core/job/integrators): lower error per frame, but a mean biased
  // upwards where the image is dark.
  bool clamp_negative = true;
  DataTerm data_term = DataTerm::kAuto;
};

// Emitters seen directly (core/render/direct_emission.h); unset: the
// integrator's default (4/16 for gpt and tgpt, 0/0 for pt).
struct DirectLightSpec {
  std::optional<int> strata;
  std::optional<int> edge_strata;
};

struct OutputSpec {
  std::vector<std::string> exr_layers;  // empty: all the integrator produces
  bool previews = true;                 // 8-bit PNG through OCIO
  std::string video_codec = "h264";     // h264 | prores | ffv1 | none
  // The EXR frames' codec, all lossless: auto | zip | zips | rle | piz | none.
  // ZIP gives the smallest files, RLE writes several times faster; auto is RLE
  // under a time budget (which pays for writing the frame, so the time goes to
  // sampling), ZIP otherwise (docs/renderer.md, "EXR codecs").
  std::string exr_compression = "auto";
  std::string ocio_display = "sRGB - Display";
  std::string ocio_view = "ACES 1.0 - SDR Video";
};

struct JobSpec {
  std::string scene;                   // .xml path (relative to the job file or the asset root)
  std::string frames = "0";            // render-farm syntax: "1-100", "1-100x2", "1,5,10-20"
  double fps = 24.0;
  int width = 0, height = 0;           // 0: the scene's hdrfilm
  int spp = 0;                         // 0: the scene's sample_count
  double time_budget_s = 0;            // per frame; 0: use spp
  uint64_t seed = 0;
  Integrator integrator = kDefaultIntegrator;
  ShiftMapping shift = kDefaultShiftMapping;                   // gpt and tgpt
  TemporalShiftMapping temporal_shift = kDefaultTemporalShift;  // tgpt
  ReconstructionSpec reconstruction;
  DirectLightSpec direct_light;
  std::map<std::string, std::string> params;  // Mitsuba <default> overrides
  Animation animation;                 // keyframed tracks
  OutputSpec outputs;
  int priority = 0;
  std::string reference;               // optional reference EXR (pattern with %04d for sequences)
};

// Parses "1-100x2,5" into a sorted list of distinct frame numbers. Errors name
// the offending token. Limit the count with `max_frames` (0: no limit).
Expected<std::vector<int>> parse_frame_range(const std::string& text, size_t max_frames = 0);

// JSON <-> JobSpec. `origin` names the source in error messages. A parsed
// job has passed validate() (core/job/job_validation.h).
Expected<JobSpec> parse_job_json(const std::string& json_text, const std::string& origin);
std::string job_to_json(const JobSpec& job);

}  // namespace gdvr
