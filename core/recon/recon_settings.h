// Options of the reconstruction (docs/reconstruction.md), with the G-PT release's
// defaults, validated once before a solve and printable for logs.
#pragma once

#include <array>
#include <string>

#include "core/recon/term.h"
#include "core/util/enum_names.h"
#include "core/util/status.h"

namespace gdvr {

enum class ReconMethod {
  kNone,      // primal only (non-finite pixels replaced by 0)
  kL2,        // screened Poisson, Jacobi-preconditioned CG
  kL1,        // IRLS of the L1 objective
  kUniform,   // image-space control variates, uniform weights (Rousselle 2016)
  kWeighted,  // image-space control variates, inverse-variance weights
};

// Whether `method` reads the constraints' variances (to weigh them); the
// others only need to know which constraints a non-finite variance drops.
inline bool uses_constraint_variances(ReconMethod method) { return method == ReconMethod::kWeighted; }

// The spellings of job files and flags ("reconstruction.method", --recon).
inline constexpr EnumNames<ReconMethod, 5> kReconMethodNames = {{{ReconMethod::kL1, "l1"},
                                                                 {ReconMethod::kL2, "l2"},
                                                                 {ReconMethod::kUniform, "uniform"},
                                                                 {ReconMethod::kWeighted, "weighted"},
                                                                 {ReconMethod::kNone, "none"}}};
inline const char* recon_method_name(ReconMethod m) { return enum_name(kReconMethodNames, m); }
inline Expected<ReconMethod> parse_recon_method(const std::string& name) {
  return parse_enum_name(kReconMethodNames, name, "recon method");
}

// Primal weight α of ‖α(Ī − I_g)‖: 0.2 in the G-PT and T-GPT releases, and
// the default of every job.
inline constexpr double kDefaultReconAlpha = 0.2;

// Tiled solve (docs/reconstruction.md, "Tiled solve"): frames wider or taller
// than this are solved in tiles of at most this many pixels a side. 640
// makes 720p 2x2 tiles holding 1.14x its pixels (512: 3x2, 1.3x, measurably
// slower than the whole-frame solve) and keeps a 1080p or 4K tile's part of a
// 20-frame window near 1.5 GB (gdvr-bench-tgpt --recon; docs/benchmarks.md,
// "Stage 2 by tiles").
inline constexpr int kDefaultReconTileSize = 640;
// Smaller tiles spend most of their work on the halo they throw away; below
// this a tile size is a typo, not a choice.
inline constexpr int kMinReconTileSize = 16;
// Overlap on each side of a tile's core, in decay lengths 1/α of the
// operator's impulse response: at α = 0.2 that is 32 px, where the measured
// response is 4e-5 of its peak and what the cut halo changes in a core is
// ~80x smaller than what the default CG tolerance itself leaves
// (docs/reconstruction.md, "Tiled solve"). The response falls below 1e-4 of
// its peak within this many decay lengths for α from 0.1 to 1 (measured).
inline constexpr double kReconTileHaloDecayLengths = 6.4;
// A large α decays faster than e^(−α r) predicts at small r, but not that
// much faster: never fewer pixels than this.
inline constexpr int kMinReconTileHalo = 12;

struct ReconSettings {
  // The library's default for a caller that builds ReconSettings itself (the
  // benchmarks, the solver tests): L2, the screened Poisson solve the other
  // methods are measured against. A job's default is L1 (kDefaultJobReconMethod
  // in core/job/job_defaults.h, the public job format's default), and a job
  // always sets `method`, so this value never reaches a job's image.
  ReconMethod method = ReconMethod::kL2;
  double alpha = kDefaultReconAlpha;
  // Extra multiplier per term (primal, dx, dy, dt, dxdt, dydt); 0 drops a term.
  std::array<double, kTermCount> term_weights = {1, 1, 1, 1, 1, 1};

  // ---- L2 (and the inner solves of L1) ----
  int l2_max_iterations = 200;
  double l2_tolerance = 1e-3;  // relative residual ‖b − Ax‖ / ‖b‖ (≈ relative error of the low frequencies)

  // ---- L1 by IRLS: weights 1/(|r| + ε_k), ε_k = ε_0 · decay^(k−1) ----
  int l1_outer_iterations = 20;
  int l1_inner_iterations = 50;
  double l1_inner_tolerance = 1e-3;
  double l1_epsilon0 = 0.05;
  double l1_epsilon_decay = 0.5;
  // Where the data term is a denoiser's image (the window carries its trust
  // map), IRLS starts from that image, already close to the answer: its first
  // reweighting finds the sampled gradients that disagree with it (the
  // outliers), and iterating on towards the exact L1 minimiser pulls each
  // pixel to the median of its constraints, which costs per-pixel error (and
  // half of stage 2's time). So that case stops after these rounds, at
  // ε = 0.01 then 0.001 (docs/reconstruction.md, "L1 from a denoised data term").
  int l1_denoised_outer_iterations = 2;
  double l1_denoised_epsilon0 = 0.01;
  double l1_denoised_epsilon_decay = 0.1;
  // Give the L1 result back the low frequencies of what it left of the primal
  // (core/recon/irls_l1.cpp): L1 alone tends to the median and loses the
  // energy of rare bright paths (−50 % on a room lit through a gap at 4 spp).
  bool l1_low_frequencies_from_primal = true;

  // ---- Control variates (uniform / weighted) ----
  int cv_iterations = 50;
  // Variances below this are clamped so inverse-variance weights stay finite.
  double variance_floor = 1e-8;

  // ---- Tiled solve (used by T-GPT's window cache and reconstruct_tiled) ----
  // 0: never tile; otherwise frames larger than tile_size in either axis are
  // solved as tiles of at most tile_size² core pixels, each over its core plus
  // tile_halo pixels per side; 0: from α (kReconTileHaloDecayLengths / α,
  // at least kMinReconTileHalo). The control variates use at least
  // cv_iterations (tiled_reconstruct.h).
  int tile_size = kDefaultReconTileSize;
  int tile_halo = 0;

  double term_weight(Term t) const { return term_weights[term_index(t)]; }
  Status validate() const;  // names the offending field
  std::string to_string() const;
};

}  // namespace gdvr
