// The named buffers of T-GPT and the temporal gradients made from them
// (named buffers, not magic indices: docs/architecture.md).
//
// Stage 1 stores per frame (tgpt_frame_layers): both half passes
// ("a_primal", "a_dx", "a_dy", "b_…", with "_var" variances), the averaged
// "direct" and "shift_failure_rate", and the motion fields "motion" (towards
// the next frame) and "motion_back" (towards the previous one). The frame's
// primal, dx, dy and variances are formed from the passes when needed
// (tgpt_frame_estimate). A frame carries
// "motion" if and only if the pair (t, t_next) changes: its absence is how
// stage 2, which sees only buffers, knows the pair is static.
//
// Stage 2 (temporal_gradients) forms, from frame t's pass B and frame
// t_next's pass A, which replay the same random numbers (pass_schedule.h):
//   dt_t   = A_{t+1}.primal − B_t.primal   ≈ I_{t+1}(p) − I_t(p)
//   dxdt_t = A_{t+1}.dx − B_t.dx,  dydt_t = A_{t+1}.dy − B_t.dy
// i.e. the same-pixel differences that core/recon's H_dt, H_dxdt, H_dydt
// expect (docs/reconstruction.md). Each is unbiased (difference of two unbiased
// estimates), and low-variance where the replay pair stays correlated.
// With motion compensation (TgptSettings::compensates_motion) the pair follows
// the surface: dt_t(p) = A_{t+1}.primal(q) − B_t.primal(p) ≈ I_{t+1}(q) − I_t(p)
// with q = p + o(p) the pixel whose pass A replayed p's stream
// (core/temporal/replay_map.h), likewise dxdt and dydt, and o goes to the
// solve as GradientFrame::temporal_target.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/recon/gradient_frame.h"
#include "core/temporal/tgpt_frame.h"
#include "core/temporal/tgpt_settings.h"

namespace gdvr {

// Stage 1 → buffers (moves the images out of `render`).
LayeredImage tgpt_frame_layers(TgptFrameRender&& render);

struct TemporalGradients {
  Image dt, dxdt, dydt;              // RGB; 0 where masked
  Image dt_var, dxdt_var, dydt_var;  // RGB
  std::vector<uint8_t> valid;        // empty: every pixel valid
  Image failure_rate;                // one channel: 1 where the temporal constraint was dropped
  // Motion-compensated pairs: X, Y = o(p) = q − p in whole pixels (0 where
  // dropped), where p's constraints land in the next frame. Empty: the same
  // pixel (no compensation, a static pair).
  Image target;
  bool static_pair = false;          // exactly zero, no subtraction done
  int64_t failed = 0;
};

// Frame t's buffers and the next frame's; kInvalidArgument names a missing layer.
Expected<TemporalGradients> temporal_gradients(const LayeredImage& t, const LayeredImage& next,
                                               const TgptSettings& settings);

// The frame's estimate `name` ("primal", "dx", "dy" or one of their "_var")
// from its two passes: (A + B)/2, variances (Var A + Var B)/4.
Expected<Image> tgpt_frame_estimate(const LayeredImage& t, const std::string& name);

// What tgpt_gradient_frame keeps of the gradients' variances.
enum class GradientVariances {
  kKeep,  // every term's variance: the weighted solver reads them
  // Only the primal's. A gradient constraint whose variance is not finite (or
  // negative) gets a NaN value instead, which drops it exactly as the kept
  // variance would (core/recon/constraint_layout.cpp), counted the same. The
  // solvers that weigh nothing by variance (l2, l1, uniform) then hold 7 RGB
  // images per frame and pixel of a window instead of 12.
  kFoldIntoValues,
};

// kKeep for the solver that weighs by variance, kFoldIntoValues otherwise.
inline GradientVariances gradient_variances_for(ReconMethod method) {
  return uses_constraint_variances(method) ? GradientVariances::kKeep : GradientVariances::kFoldIntoValues;
}

// The reconstruction's view of frame t: primal, dx, dy (and variances) from
// the buffers, plus dt, dxdt, dydt when `temporal` is given (with its mask on
// all three temporal terms and its target as the frame's temporal_target; its
// images are moved from). The primal is the
// buffers' denoised data term with its trust map where they carry one and
// `data_term` is not kSampled (TgptSettings::data_term); kDenoised on buffers
// without one is FAILED_PRECONDITION.
Expected<GradientFrame> tgpt_gradient_frame(const LayeredImage& t, TemporalGradients* temporal,
                                            GradientVariances variances = GradientVariances::kKeep,
                                            DataTerm data_term = DataTerm::kAuto);

}  // namespace gdvr
