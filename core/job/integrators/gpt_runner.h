// Gradient-domain path tracing in a job (docs/gpt.md): stage 1 samples each
// frame's primal, gradients, direct light and their variances; stage 2
// reconstructs the indirect part of that frame alone and adds the direct
// light, which is kept out of the solve (docs/gpt.md, "Direct light").
#pragma once

#include <memory>

#include "core/gradient/gpt_settings.h"
#include "core/job/integrators/integrator_runner.h"

namespace gdvr {

class GptRunner final : public IntegratorRunner {
 public:
  // The job's shift and reconstruction as G-PT settings, checked.
  static Expected<std::unique_ptr<GptRunner>> create(const JobSpec& job);

  Status render(const FrameRenderContext& context, int frame, FrameBuffers* out) override;
  Expected<FrameOutput> finalize(int frame, const std::map<int, FrameBuffers>& buffers) override;

 private:
  GptRunner(GptSettings settings, bool clamp_negative) : settings_(std::move(settings)), clamp_negative_(clamp_negative) {}

  GptSettings settings_;
  bool clamp_negative_;
};

}  // namespace gdvr
