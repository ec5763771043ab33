#include "core/job/integrators/gradient_domain_frame.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace gdvr {

ReconSettings job_recon_settings(const ReconstructionSpec& spec, ReconSettings base) {
  base.method = spec.method;
  base.alpha = spec.alpha;
  base.tile_size = spec.tile_size;
  if (spec.term_weights.size() == size_t(kTermCount))
    for (int t = 0; t < kTermCount; ++t) base.term_weights[size_t(t)] = spec.term_weights[size_t(t)];
  return base;
}

int64_t add_direct_clamped(const Image& direct, bool clamp, Image* final_image) {
  int64_t bad = 0;
  for (size_t k = 0; k < final_image->data().size(); ++k) {
    const float d = direct.data()[k];
    float& v = final_image->data()[k];
    if (std::isfinite(d)) v += d;
    else ++bad;
    if (clamp) v = std::max(v, 0.0f);
  }
  return bad;
}

void zero_non_finite_layers(FrameOutput* out) {
  int64_t bad = 0;
  for (ImageLayer& l : out->image.layers)
    for (float& v : l.image.data())
      if (!std::isfinite(v)) v = 0.0f, ++bad;
  if (bad > 0) out->stats.left_out.push_back(std::to_string(bad) + " non-finite buffer values zeroed in the output layers");
}

void note_unused_glossy_shift(const Scene& scene, const GptSettings& gpt, FrameStats* stats) {
  bool glossy = false;
  for (const Bsdf& bsdf : scene.bsdfs) glossy = glossy || bsdf.roughness() <= gpt.diffuse_roughness;
  if (!glossy && gpt.shift != ShiftMapping::kReplay)
    stats->left_out.push_back("glossy shift machinery: no glossy or specular BSDF in the scene");
}

}  // namespace gdvr
