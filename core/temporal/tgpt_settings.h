// Options of the temporal gradient-domain path tracer (T-GPT, Manzi et al.
// 2016; docs/tgpt.md): the spatial G-PT options of each half pass, how
// temporal constraints follow motion, and the sliding-window reconstruction.
// Validated once before a job; printable for logs.
#pragma once

#include <string>

#include "core/gradient/gpt_settings.h"
#include "core/recon/recon_settings.h"
#include "core/util/enum_names.h"
#include "core/util/status.h"

namespace gdvr {

// How the temporal gradient dt is sampled (docs/tgpt.md):
enum class TemporalShiftMapping {
  // replay: pass B of frame t and pass A of t+1 share their random numbers;
  // dt = A_{t+1} − B_t (the public T-GPT code).
  kReplay,
  // reconnect: the path-space shift (core/gradient/temporal_reconnection_shift.h):
  // pass B's base paths shifted into t+1 and pass A's into t−1 (the two
  // generations of every pair, balance-heuristic MIS); dxdt, dydt still come
  // from the replay pair.
  kReconnect,
};
// The spellings of job files and flags ("temporal_shift", --temporal-shift).
inline constexpr EnumNames<TemporalShiftMapping, 2> kTemporalShiftNames = {
    {{TemporalShiftMapping::kReplay, "replay"}, {TemporalShiftMapping::kReconnect, "reconnect"}}};
inline const char* temporal_shift_name(TemporalShiftMapping m) { return enum_name(kTemporalShiftNames, m); }
inline Expected<TemporalShiftMapping> parse_temporal_shift(const std::string& name) {
  return parse_enum_name(kTemporalShiftNames, name, "temporal_shift");
}

// Replay, as the public T-GPT code: on the demo shot the path-space shift cost
// 29 % more per sample and was worse at equal time (docs/benchmarks.md, T-GPT).
inline constexpr TemporalShiftMapping kDefaultTemporalShift = TemporalShiftMapping::kReplay;
// Frames per reconstruction window (W): the T-GPT release's.
inline constexpr int kDefaultWindowFrames = 20;

// The data term of T-GPT's window solve (docs/tgpt.md, "The denoised data
// term"): the sampled primal, or the primal denoised with the frame's feature
// buffers and trusted pixel by pixel as far as the sampled gradients agree
// with it. kAuto: denoised when the process that renders a frame has a
// denoiser, sampled (and said so in the frame's left-out notes) when it has
// none. Stage 1 adds the denoised term to a frame's buffers
// (core/temporal/denoised_data_term.h); TgptSettings::data_term says what the
// window solve reads of it.
enum class DataTerm { kAuto, kSampled, kDenoised };
inline constexpr EnumNames<DataTerm, 3> kDataTermNames = {
    {{DataTerm::kAuto, "auto"}, {DataTerm::kSampled, "sampled"}, {DataTerm::kDenoised, "denoised"}}};
inline const char* data_term_name(DataTerm d) { return enum_name(kDataTermNames, d); }

struct TgptSettings {
  // The spatial sampler of both half passes (its `recon` is ignored: the
  // window solve below uses `recon`). See gpt_defaults_for().
  GptSettings gpt = gpt_defaults_for(kDefaultShiftMapping);

  TemporalShiftMapping temporal_shift = kDefaultTemporalShift;

  // What the window solve takes as its data term (tgpt_gradient_frame):
  // kSampled the sampled primal, even where the buffers carry a denoised
  // term; kDenoised the denoised term, which every frame must carry; kAuto
  // the denoised term where the window's frames carry it, all or none.
  DataTerm data_term = DataTerm::kAuto;

  // ---- Motion vectors (primary-hit reprojection, docs/tgpt.md "dt and motion") ----
  // Off: every temporal constraint is kept (same-pixel dt is unbiased anyway).
  bool motion_vectors = true;
  // Forward/backward consistency of same-pixel constraints:
  // |m_fwd(p) + m_bwd(p + m_fwd(p))| ≤ this, per axis, in whole pixels (±1 px
  // in the public code). Compensated pairs need an exact round trip.
  int consistency_tolerance_px = 1;
  // Motion-compensated temporal constraints (Manzi et al. 2016; docs/tgpt.md,
  // "dt and motion"): pass A of frame t+1 replays, at pixel q, the stream of
  // pass B of frame t at the pixel the surface came from (the backward motion
  // field), with the sub-pixel position rotated by the motion's fraction
  // (core/temporal/replay_map.h); stage 2 pairs A_{t+1}(q) with B_t(p),
  // q = p + m(p), and tells the solve where each constraint lands
  // (GradientFrame::temporal_target). On a pan over texture a same-pixel pair
  // sees different texels and dt is as noisy as a primal; the compensated
  // pair follows the surface. Only with temporal_shift replay and
  // motion_vectors on; with reconnect or motion_vectors off it is ignored and
  // dt stays the same-pixel difference below.
  bool motion_compensation = true;
  // The same-pixel dt is I_{t+1}(p) − I_t(p) (motion_compensation off, or
  // where it does not apply), so the replay pair is only correlated while the
  // surface seen through p moves by at most this many whole pixels; beyond it
  // the constraint is dropped (docs/tgpt.md, "dt and motion"). < 0: no limit.
  // Compensated constraints have no such limit.
  int max_same_pixel_motion_px = 1;
  // Whether stage 1 renders pass A with the replay map and stage 2 pairs
  // along the motion (see motion_compensation).
  bool compensates_motion() const {
    return motion_compensation && motion_vectors && temporal_shift == TemporalShiftMapping::kReplay;
  }

  // ---- Sliding-window reconstruction (docs/reconstruction.md, "Sliding windows") ----
  ReconSettings recon;
  int window = kDefaultWindowFrames;  // W ≥ 1; W = 1 is spatial G-PT
  int hop = 0;      // H, frames between window starts; 0 = max(1, W/2)
  int effective_hop() const { return hop > 0 ? hop : (window / 2 > 0 ? window / 2 : 1); }

  // G-PT's defaults for `shift`, but with cached-path Russian roulette off:
  // RR multiplies the gradient variance ~13× on cbox, and G-PT's L2 result at
  // equal time is several times better without it (docs/benchmarks.md, G-PT);
  // T-GPT reconstructs with L2 by default and its dxdt, dydt inherit the
  // spatial gradients' noise. Per-pixel sub-pixel positions too: with the
  // shared position (GptSettings::shared_jitter) the demo shot's relMSE was
  // 27 % higher at equal spp (0.00102 vs 0.00080, gdvr-bench-tgpt),
  // more than the 4-14 % it saves in time: the two generations of a pair
  // share their first hits, and the anti-aliasing error, correlated between
  // neighbours, is low-frequency error the L2 solve takes from the primal.
  static GptSettings gpt_defaults_for(ShiftMapping shift) {
    GptSettings g = GptSettings::defaults_for(shift);
    g.cached_rr = false;
    g.shared_jitter = false;
    return g;
  }

  Status validate() const;  // names the offending field
  std::string to_string() const;
};

}  // namespace gdvr
