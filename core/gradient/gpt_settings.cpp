#include "core/gradient/gpt_settings.h"

#include <cmath>
#include <sstream>

namespace gdvr {

GptSettings GptSettings::defaults_for(ShiftMapping shift) {
  GptSettings s;
  s.shift = shift;
  s.cached_rr = shift != ShiftMapping::kReplay;
  return s;
}

Status GptSettings::validate() const {
  if (!(cached_rr_min_q > 0.0f) || !(cached_rr_min_q <= 1.0f))
    return invalid_argument("gpt settings: cached_rr_min_q must lie in (0, 1], got " + std::to_string(cached_rr_min_q));
  if (!std::isfinite(diffuse_roughness) || diffuse_roughness < 0)
    return invalid_argument("gpt settings: diffuse_roughness must be finite and >= 0, got " +
                            std::to_string(diffuse_roughness));
  if (!std::isfinite(mis_epsilon) || mis_epsilon < 0 || mis_epsilon > 1e-3)
    return invalid_argument("gpt settings: mis_epsilon must lie in [0, 1e-3], got " + std::to_string(mis_epsilon));
  return recon.validate().with_context("gpt settings: ");
}

std::string GptSettings::to_string() const {
  std::ostringstream os;
  os << "shift=" << shift_mapping_name(shift) << " cached_rr=" << (cached_rr ? "on" : "off")
     << " q_min=" << cached_rr_min_q << " shared_jitter=" << (shared_jitter ? "on" : "off")
     << " pair_primal=" << (pair_primal ? "on" : "off")
     << " diffuse_roughness=" << diffuse_roughness << " mis_epsilon=" << mis_epsilon
     << " recon=" << recon_method_name(recon.method) << " alpha=" << recon.alpha;
  return os.str();
}

}  // namespace gdvr
