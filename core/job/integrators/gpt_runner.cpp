#include "core/job/integrators/gpt_runner.h"

#include "core/gradient/gpt_integrator.h"
#include "core/job/integrators/budgeted_sampling.h"
#include "core/job/integrators/gradient_domain_frame.h"
#include "core/recon/reconstruct.h"

namespace gdvr {

Expected<std::unique_ptr<GptRunner>> GptRunner::create(const JobSpec& job) {
  GptSettings settings = GptSettings::defaults_for(job.shift);
  settings.recon = job_recon_settings(job.reconstruction, settings.recon);
  GDVR_RETURN_IF_ERROR(settings.validate().with_context("job: "));
  return std::unique_ptr<GptRunner>(new GptRunner(std::move(settings), job.reconstruction.clamp_negative));
}

Status GptRunner::render(const FrameRenderContext& context, int frame, FrameBuffers* out) {
  auto result =
      render_frame_gpt(context.scene, budgeted_render_settings(context), settings_, uint32_t(frame), context.control);
  if (!result.ok()) return result.status();
  GptFrameResult& r = result.value();
  record_budgeted_sampling(context, r.spp, r.sampling_seconds);
  GradientFilmBuffers& b = r.buffers;
  out->layers.add("primal", {"R", "G", "B"}, std::move(b.primal));
  out->layers.add("dx", {"R", "G", "B"}, std::move(b.dx));
  out->layers.add("dy", {"R", "G", "B"}, std::move(b.dy));
  out->layers.add("direct", {"R", "G", "B"}, std::move(b.direct));
  out->layers.add("shift_failure_rate", {"Y"}, std::move(b.shift_failure_rate));
  out->layers.add("primal_var", {"R", "G", "B"}, std::move(b.primal_var));
  out->layers.add("dx_var", {"R", "G", "B"}, std::move(b.dx_var));
  out->layers.add("dy_var", {"R", "G", "B"}, std::move(b.dy_var));
  FrameStats& st = out->stats;
  record_render_stats(r, "non-finite samples or gradients dropped", &st);
  note_unused_glossy_shift(context.scene.scene(), settings_, &st);
  st.left_out.push_back("temporal gradients: integrator gpt (spatial only)");
  return Status::Ok();
}

Expected<FrameOutput> GptRunner::finalize(int frame, const std::map<int, FrameBuffers>& buffers) {
  auto it = buffers.find(frame);
  if (it == buffers.end()) return failed_precondition("finalize: no buffers for frame " + std::to_string(frame));
  const FrameBuffers& fb = it->second;
  FrameOutput out;
  out.frame = frame;
  out.stats = fb.stats;
  auto layer = [&](const char* name) -> const Image* {
    const ImageLayer* l = fb.layers.find(name);
    return l ? &l->image : nullptr;
  };
  for (const char* name : {"primal", "dx", "dy", "direct", "primal_var", "dx_var", "dy_var"})
    if (!layer(name)) return invalid_argument(std::string("finalize: frame buffers lack the '") + name + "' layer");
  GradientFrame gf;
  gf.buffer(Term::kPrimal) = *layer("primal");
  gf.buffer(Term::kDx) = *layer("dx");
  gf.buffer(Term::kDy) = *layer("dy");
  gf.variance(Term::kPrimal) = *layer("primal_var");
  gf.variance(Term::kDx) = *layer("dx_var");
  gf.variance(Term::kDy) = *layer("dy_var");
  auto solved = reconstruct_frame(gf, settings_.recon);
  if (!solved.ok()) return solved.status().with_context("frame " + std::to_string(frame) + ": reconstruction: ");
  Image final_image = std::move(solved->frames.front());
  const int64_t bad_direct = add_direct_clamped(*layer("direct"), clamp_negative_, &final_image);
  if (bad_direct > 0)
    out.stats.left_out.push_back(std::to_string(bad_direct) + " non-finite direct-light values dropped");
  out.image.add("", {"R", "G", "B"}, std::move(final_image));
  for (const ImageLayer& l : fb.layers.layers) out.image.layers.push_back(l);
  zero_non_finite_layers(&out);
  out.stats.reconstruct_seconds = solved->stats.seconds;
  if (solved->stats.total_non_finite() > 0)
    out.stats.left_out.push_back(std::to_string(solved->stats.total_non_finite()) +
                                 " non-finite constraints dropped by the reconstruction");
  return out;
}

}  // namespace gdvr
