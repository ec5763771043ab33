#include "core/job/integrators/pt_runner.h"

#include "core/job/integrators/budgeted_sampling.h"
#include "core/render/vector_batch.h"

namespace gdvr {

Status PtRunner::render(const FrameRenderContext& context, int frame, FrameBuffers* out) {
  auto result = render_frame_pt(context.scene, budgeted_render_settings(context), uint32_t(frame), context.control);
  if (!result.ok()) return result.status();
  FrameRenderResult& r = result.value();
  record_budgeted_sampling(context, r.spp, r.sampling_seconds);
  out->layers.add("", {"R", "G", "B"}, std::move(r.color));
  out->layers.add("direct", {"R", "G", "B"}, std::move(r.direct));
  out->layers.add("variance", {"R", "G", "B"}, std::move(r.variance));
  FrameStats& st = out->stats;
  record_render_stats(r, "non-finite samples dropped", &st);
  st.left_out.push_back("gradient sampling and reconstruction: integrator pt");
  const std::string scalar_why =
      why_no_vector_batch(context.scene, context.settings.path, context.settings.paths_in_flight);
  if (!scalar_why.empty()) st.left_out.push_back("the vector path batch's AVX2/AVX-512 kernel: " + scalar_why);
  return Status::Ok();
}

Expected<FrameOutput> PtRunner::finalize(int frame, const std::map<int, FrameBuffers>& buffers) {
  auto it = buffers.find(frame);
  if (it == buffers.end()) return failed_precondition("finalize: no buffers for frame " + std::to_string(frame));
  FrameOutput out;
  out.frame = frame;
  out.stats = it->second.stats;
  out.image = it->second.layers;
  return out;
}

}  // namespace gdvr
