#include "core/temporal/denoised_data_term.h"

#include <cmath>

#include "core/recon/data_term_weight.h"
#include "core/render/feature_buffers.h"
#include "core/temporal/temporal_buffers.h"

namespace gdvr {

Status add_denoised_data_term(const FrameDenoiser& denoise, LayeredImage* frame) {
  if (!denoise) return failed_precondition("denoised data term: no denoiser");
  const ImageLayer* albedo = frame->find(kAlbedoLayer);
  const ImageLayer* normal = frame->find(kNormalLayer);
  if (!albedo || !normal) return internal_error("denoised data term: the frame has no albedo and normal layers");
  auto primal = tgpt_frame_estimate(*frame, "primal");
  if (!primal.ok()) return primal.status();
  auto denoised = denoise(primal.value(), albedo->image, normal->image);
  if (!denoised.ok()) return denoised.status().with_context("denoised data term: ");
  const Image& d = denoised.value();
  if (d.width() != primal->width() || d.height() != primal->height() || d.channels() != primal->channels())
    return internal_error("denoised data term: the denoiser returned an image of another shape");
  for (float v : d.data())
    if (!std::isfinite(v)) return internal_error("denoised data term: the denoiser returned a non-finite value");
  const ImageLayer* gradients[4] = {frame->find("a_dx"), frame->find("b_dx"), frame->find("a_dy"), frame->find("b_dy")};
  for (const ImageLayer* g : gradients)
    if (!g) return internal_error("denoised data term: the frame lacks a pass's spatial gradients");
  auto weight = data_term_weight(d, gradients[0]->image, gradients[1]->image, gradients[2]->image, gradients[3]->image);
  if (!weight.ok()) return weight.status();
  frame->add(kDataWeightLayer, {"Y"}, std::move(weight.value()));
  frame->add(kDenoisedPrimalLayer, {"R", "G", "B"}, std::move(denoised.value()));
  return Status::Ok();
}

}  // namespace gdvr
