#include "core/job/integrators/budgeted_sampling.h"

#include <algorithm>

namespace gdvr {

FrameRenderSettings budgeted_render_settings(const FrameRenderContext& context) {
  FrameRenderSettings s = context.settings;
  FrameTimeBudget* budget = context.budget;
  if (!budget) return s;
  const int pass_size = std::max(1, context.settings.spp);
  if (!budget->has_sample_cost()) {
    // A budget > 0 renders at least one pass, however small the allowance.
    s.time_budget_s = std::max(budget->render_seconds(), 1e-6);
  } else {
    s.time_budget_s = 0;
    s.spp = budget->take_count(budget->samples_in(budget->sampling_seconds()), pass_size);
  }
  return s;
}

void record_budgeted_sampling(const FrameRenderContext& context, int spp, double sampling_seconds) {
  if (context.budget) context.budget->record_sampling(spp, sampling_seconds);
}

}  // namespace gdvr
