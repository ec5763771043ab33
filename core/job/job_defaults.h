// What a field left out of a job means, and the range a given value must lie
// in: the job format's own defaults and limits (core/job/job_spec.h,
// proto/gdvr/v1/job.proto, README "Job files"). Defaults of the renderer's
// settings are named where those settings live (core/recon, core/gradient,
// core/temporal, core/scene) and JobSpec takes them from there, so each
// value is written once.
#pragma once

#include "core/job/integrators/integrator.h"
#include "core/recon/recon_settings.h"
#include "core/scene/scene.h"

namespace gdvr {

// ---- Defaults ----
inline constexpr Integrator kDefaultIntegrator = Integrator::kPt;
// L1, as the public job format has always had it: the G-PT paper's choice for
// final images, where L2 (unbiased) spreads outlier gradients into visible
// artifacts. ReconSettings' own default (L2) is the library's, for callers
// that solve directly.
inline constexpr ReconMethod kDefaultJobReconMethod = ReconMethod::kL1;

// ---- Limits ----
inline constexpr int kMaxJobResolution = kMaxFilmResolution;  // width, height
inline constexpr int kMaxJobSpp = 1 << 20;
inline constexpr double kMaxJobFps = 1000;
inline constexpr int kMaxWindowFrames = 1000;   // reconstruction.window
inline constexpr int kMaxDirectStrata = 64;     // direct_light.strata, edge_strata
inline constexpr double kMaxTermWeight = 1e6;   // reconstruction.term_weights[i]

}  // namespace gdvr
