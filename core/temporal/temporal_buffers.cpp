#include "core/temporal/temporal_buffers.h"

#include <cmath>
#include <limits>
#include <string>
#include <tuple>

#include "core/temporal/denoised_data_term.h"
#include "core/temporal/replay_map.h"

namespace gdvr {
namespace {

const std::vector<std::string> kRgb = {"R", "G", "B"};

Image average(const Image& a, const Image& b, float scale) {
  Image out(a.width(), a.height(), a.channels());
  for (size_t i = 0; i < out.data().size(); ++i) out.data()[i] = scale * (a.data()[i] + b.data()[i]);
  return out;
}

Image difference(const Image& next, const Image& cur) {
  Image out(cur.width(), cur.height(), cur.channels());
  for (size_t i = 0; i < out.data().size(); ++i) out.data()[i] = next.data()[i] - cur.data()[i];
  return out;
}

// Var(A − B) ≤ Var A + Var B + 2·sqrt(Var A·Var B); we use Var A + Var B, which
// ignores the (positive, wanted) correlation of the replay pair: an upper bound
// for a positively correlated pair, i.e. the weighted solver trusts dt less
// than it could. The half buffers that would measure it are not kept.
Image sum(const Image& a, const Image& b) { return average(a, b, 1.0f); }

// next(p + target(p)) + sign · cur(p) where p has its replayed pair. Elsewhere
// the value is 0, so that the EXR layers show what the solve uses, and a
// variance (sign +1) is the same-pixel one, as without compensation.
Image paired(const Image& next, const Image& cur, const ReplayPairs& pairs, float sign) {
  const int w = cur.width(), h = cur.height(), C = cur.channels();
  const bool variance = sign > 0;
  Image out(w, h, C);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool paired = pairs.valid[size_t(y) * size_t(w) + size_t(x)] != 0;
      if (!paired && !variance) continue;
      const int qx = paired ? x + int(pairs.target.at(x, y, 0)) : x;
      const int qy = paired ? y + int(pairs.target.at(x, y, 1)) : y;
      for (int c = 0; c < C; ++c) out.at(x, y, c) = next.at(qx, qy, c) + sign * cur.at(x, y, c);
    }
  return out;
}
Image paired_difference(const Image& next, const Image& cur, const ReplayPairs& pairs) {
  return paired(next, cur, pairs, -1.0f);
}
// Var next(q) + Var cur(p): the same upper bound as sum().
Image paired_sum(const Image& next_var, const Image& cur_var, const ReplayPairs& pairs) {
  return paired(next_var, cur_var, pairs, 1.0f);
}

}  // namespace

LayeredImage tgpt_frame_layers(TgptFrameRender&& r) {
  LayeredImage L;
  GradientFilmBuffers& a = r.a;
  GradientFilmBuffers& b = r.b;
  // The frame's own estimates (primal, dx, dy = (A + B)/2) are not stored:
  // tgpt_frame_estimate() forms them from the passes, which saves 7 of ~20
  // RGB layers per buffered frame (stage 2 holds about W frames).
  L.add("direct", kRgb, r.direct.empty() ? average(a.direct, b.direct, 0.5f) : std::move(r.direct));
  L.add("shift_failure_rate", {"Y"}, average(a.shift_failure_rate, b.shift_failure_rate, 0.5f));
  // ---- The passes, for the temporal differences of stage 2 ----
  for (auto [prefix, p] : {std::pair<const char*, GradientFilmBuffers*>{"a_", &a}, {"b_", &b}}) {
    const std::string s = prefix;
    L.add(s + "primal", kRgb, std::move(p->primal));
    L.add(s + "dx", kRgb, std::move(p->dx));
    L.add(s + "dy", kRgb, std::move(p->dy));
    L.add(s + "primal_var", kRgb, std::move(p->primal_var));
    L.add(s + "dx_var", kRgb, std::move(p->dx_var));
    L.add(s + "dy_var", kRgb, std::move(p->dy_var));
  }
  // ---- Path-space temporal shift (reconnect): one generation each way ----
  // dt_fwd: pass B's bases shifted into t+1, ≈ I_{t+1} − I_t; dt_bwd: pass A's
  // bases shifted into t−1, negated, ≈ I_t − I_{t−1}.
  if (!b.temporal.empty()) {
    L.add("dt_fwd", kRgb, std::move(b.temporal));
    L.add("dt_fwd_var", kRgb, std::move(b.temporal_var));
    L.add("dt_fwd_failures", {"Y"}, std::move(b.temporal_failure_rate));
  }
  if (!a.temporal.empty()) {
    for (float& x : a.temporal.data()) x = -x;
    L.add("dt_bwd", kRgb, std::move(a.temporal));
    L.add("dt_bwd_var", kRgb, std::move(a.temporal_var));
    L.add("dt_bwd_failures", {"Y"}, std::move(a.temporal_failure_rate));
  }
  if (!r.forward.offsets.empty()) L.add("motion", {"X", "Y", "V"}, std::move(r.forward.offsets));
  if (!r.backward.offsets.empty()) L.add("motion_back", {"X", "Y", "V"}, std::move(r.backward.offsets));
  return L;
}

Expected<TemporalGradients> temporal_gradients(const LayeredImage& t, const LayeredImage& next,
                                               const TgptSettings& settings) {
  auto need = [](const LayeredImage& L, const char* name, const char* which) -> Expected<const Image*> {
    const ImageLayer* l = L.find(name);
    if (!l) return invalid_argument(std::string("tgpt: ") + which + " frame's buffers lack the '" + name + "' layer");
    return &l->image;
  };
  auto primal = need(t, "b_primal", "this");
  if (!primal.ok()) return primal.status();
  const int w = primal.value()->width(), h = primal.value()->height();
  TemporalGradients g;
  g.failure_rate = Image(w, h, 1);
  const ImageLayer* forward = t.find("motion");
  if (!forward) {
    // Static pair: the replayed offset would be the base path itself
    // (docs/tgpt.md, "Leaving out what the scene does not need").
    g.static_pair = true;
    for (Image* im : {&g.dt, &g.dxdt, &g.dydt, &g.dt_var, &g.dxdt_var, &g.dydt_var}) *im = Image(w, h, 3);
    return g;
  }
  const char* names[3] = {"primal", "dx", "dy"};
  Image* values[3] = {&g.dt, &g.dxdt, &g.dydt};
  Image* vars[3] = {&g.dt_var, &g.dxdt_var, &g.dydt_var};
  // Path-space dt (reconnect): the two generations of each pair, t's forward
  // and t+1's backward; their MIS weights sum to one, so the sum estimates
  // I_{t+1} − I_t. dxdt, dydt stay the replay differences below.
  const ImageLayer* fwd = t.find("dt_fwd");
  Image shift_failures;
  if (fwd) {
    const ImageLayer* bwd = next.find("dt_bwd");
    const ImageLayer* fwd_var = t.find("dt_fwd_var");
    const ImageLayer* bwd_var = next.find("dt_bwd_var");
    const ImageLayer* fwd_fail = t.find("dt_fwd_failures");
    const ImageLayer* bwd_fail = next.find("dt_bwd_failures");
    if (!bwd || !fwd_var || !bwd_var || !fwd_fail || !bwd_fail)
      return invalid_argument("tgpt: this frame has a forward temporal shift ('dt_fwd') but the next frame's buffers "
                              "lack 'dt_bwd' (or a variance/failure layer): both must be rendered with temporal_shift "
                              "reconnect");
    if (bwd->image.data().size() != fwd->image.data().size())
      return invalid_argument("tgpt: the next frame's buffers have a different size");
    g.dt = sum(fwd->image, bwd->image);
    g.dt_var = sum(fwd_var->image, bwd_var->image);
    shift_failures = average(fwd_fail->image, bwd_fail->image, 0.5f);
  }
  const ImageLayer* backward = settings.motion_vectors ? next.find("motion_back") : nullptr;
  if (settings.motion_vectors && !backward)
    return invalid_argument("tgpt: the next frame's buffers lack 'motion_back' although this frame has 'motion'");
  if (backward && (backward->image.width() != w || backward->image.height() != h ||
                   forward->image.width() != w || forward->image.height() != h))
    return invalid_argument("tgpt: the motion fields ('motion', 'motion_back') differ in size from the passes");
  // Motion-compensated pairs (replay only): A_{t+1} at q = p + m(p), the
  // pixel whose pass A replayed B_t's stream at p (core/temporal/replay_map.h).
  const bool compensate = settings.compensates_motion() && !fwd;
  ReplayPairs pairs;
  if (compensate) pairs = replay_pairs(forward->image, backward->image);
  for (int k = fwd ? 1 : 0; k < 3; ++k) {
    const std::string n = names[k];
    auto bt = need(t, ("b_" + n).c_str(), "this");
    auto an = need(next, ("a_" + n).c_str(), "next");
    auto bt_var = need(t, ("b_" + n + "_var").c_str(), "this");
    auto an_var = need(next, ("a_" + n + "_var").c_str(), "next");
    for (auto* e : {&bt, &an, &bt_var, &an_var})
      if (!e->ok()) return e->status();
    if (an.value()->width() != w || an.value()->height() != h)
      return invalid_argument("tgpt: the next frame's buffers have a different size");
    if (compensate) {
      *values[k] = paired_difference(*an.value(), *bt.value(), pairs);
      *vars[k] = paired_sum(*an_var.value(), *bt_var.value(), pairs);
    } else {
      *values[k] = difference(*an.value(), *bt.value());
      *vars[k] = sum(*an_var.value(), *bt_var.value());
    }
  }
  if (compensate) {
    g.failed = pairs.failed;
    g.failure_rate = std::move(pairs.failure);
    g.valid = std::move(pairs.valid);
    g.target = std::move(pairs.target);
    return g;
  }
  if (backward) {
    TemporalMask mask = temporal_consistency(forward->image, backward->image, settings);
    g.failed = mask.failed;
    g.failure_rate = std::move(mask.failure);
    // Where the constraint is kept, the rate of failed path-space shifts.
    if (!shift_failures.empty())
      for (size_t p = 0; p < mask.valid.size(); ++p)
        if (mask.valid[p]) g.failure_rate.data()[p] = shift_failures.data()[p];
    // Zero the dropped values too, so the EXR layers show what the solve uses.
    for (size_t p = 0; p < mask.valid.size(); ++p)
      if (!mask.valid[p])
        for (Image* im : values)
          for (int c = 0; c < 3; ++c) im->data()[p * 3 + c] = 0.0f;
    g.valid = std::move(mask.valid);
  } else if (!shift_failures.empty()) {
    g.failure_rate = std::move(shift_failures);
  }
  return g;
}

Expected<Image> tgpt_frame_estimate(const LayeredImage& t, const std::string& name) {
  const ImageLayer* a = t.find("a_" + name);
  const ImageLayer* b = t.find("b_" + name);
  if (!a || !b) return invalid_argument("tgpt: frame buffers lack 'a_" + name + "' or 'b_" + name + "'");
  if (a->image.data().size() != b->image.data().size())
    return invalid_argument("tgpt: passes of '" + name + "' differ in size");
  // Mean of the two independent passes; Var((A + B)/2) = (Var A + Var B)/4.
  const bool variance = name.size() > 4 && name.compare(name.size() - 4, 4, "_var") == 0;
  return average(a->image, b->image, variance ? 0.25f : 0.5f);
}

namespace {

// NaN in every channel of a pixel whose variance is not finite or negative in
// any channel: constraint_layout.cpp drops such a constraint either way.
void fold_variance_into_values(const Image& variance, Image* values) {
  if (variance.data().size() != values->data().size()) return;  // none measured: nothing to drop
  const int C = values->channels();
  const float* var = variance.data().data();
  float* v = values->data().data();
  for (size_t p = 0; p < values->pixel_count(); ++p) {
    bool good = true;
    for (int c = 0; c < C; ++c) good &= std::isfinite(var[p * C + c]) && var[p * C + c] >= 0;
    if (!good)
      for (int c = 0; c < C; ++c) v[p * C + c] = std::numeric_limits<float>::quiet_NaN();
  }
}

}  // namespace

Expected<GradientFrame> tgpt_gradient_frame(const LayeredImage& t, TemporalGradients* temporal,
                                            GradientVariances variances, DataTerm data_term) {
  const bool keep = variances == GradientVariances::kKeep;
  GradientFrame gf;
  const std::pair<Term, const char*> spatial[3] = {{Term::kPrimal, "primal"}, {Term::kDx, "dx"}, {Term::kDy, "dy"}};
  for (auto [term, name] : spatial) {
    auto v = tgpt_frame_estimate(t, name);
    auto var = tgpt_frame_estimate(t, std::string(name) + "_var");
    if (!v.ok()) return v.status();
    if (!var.ok()) return var.status();
    gf.buffer(term) = std::move(v.value());
    // A denoised data term replaces the sampled primal in the solve, with
    // its per-pixel trust (core/temporal/denoised_data_term.h); the sampled
    // primal's variance stays (only the weighted method reads it).
    if (term == Term::kPrimal && data_term != DataTerm::kSampled) {
      const ImageLayer* denoised = t.find(kDenoisedPrimalLayer);
      const ImageLayer* weight = t.find(kDataWeightLayer);
      if (denoised && weight) {
        gf.buffer(term) = denoised->image;
        gf.data_weight = weight->image;
      } else if (data_term == DataTerm::kDenoised) {
        return failed_precondition(
            std::string("data_term 'denoised': the buffers carry no denoised data term (layers '") +
            kDenoisedPrimalLayer + "', '" + kDataWeightLayer +
            "'): they were rendered with data_term 'sampled' or where there was no denoiser; render them again "
            "with one, or reconstruct with data_term 'auto' or 'sampled'");
      }
    }
    if (keep || term == Term::kPrimal)
      gf.variance(term) = std::move(var.value());
    else
      fold_variance_into_values(var.value(), &gf.buffer(term));
  }
  if (temporal) {
    const std::tuple<Term, Image*, Image*> terms[3] = {{Term::kDt, &temporal->dt, &temporal->dt_var},
                                                      {Term::kDxdt, &temporal->dxdt, &temporal->dxdt_var},
                                                      {Term::kDydt, &temporal->dydt, &temporal->dydt_var}};
    for (auto [term, value, var] : terms) {
      gf.buffer(term) = std::move(*value);
      if (keep)
        gf.variance(term) = std::move(*var);
      else
        fold_variance_into_values(*var, &gf.buffer(term));
    }
    if (!temporal->valid.empty())
      for (Term term : {Term::kDt, Term::kDxdt, Term::kDydt}) gf.mask(term) = temporal->valid;
    gf.temporal_target = std::move(temporal->target);
  }
  GDVR_RETURN_IF_ERROR(gf.validate());
  return gf;
}

}  // namespace gdvr
