// Path tracing in a job: stage 1 renders the final image (with its direct
// light and variance layers), so stage 2 only hands the buffers on.
#pragma once

#include "core/job/integrators/integrator_runner.h"

namespace gdvr {

class PtRunner final : public IntegratorRunner {
 public:
  Status render(const FrameRenderContext& context, int frame, FrameBuffers* out) override;
  Expected<FrameOutput> finalize(int frame, const std::map<int, FrameBuffers>& buffers) override;
};

}  // namespace gdvr
