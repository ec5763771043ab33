#include "core/recon/recon_settings.h"

#include <cmath>
#include <sstream>

namespace gdvr {

namespace {
Status positive_finite(double v, const char* field) {
  if (!std::isfinite(v) || v <= 0)
    return invalid_argument(std::string("recon settings: ") + field + " must be finite and > 0, got " +
                            std::to_string(v));
  return Status::Ok();
}
Status at_least(int v, int lo, const char* field) {
  if (v < lo)
    return invalid_argument(std::string("recon settings: ") + field + " must be >= " + std::to_string(lo) +
                            ", got " + std::to_string(v));
  return Status::Ok();
}
}  // namespace

Status ReconSettings::validate() const {
  GDVR_RETURN_IF_ERROR(positive_finite(alpha, "alpha"));
  for (Term t : kAllTerms) {
    const double w = term_weight(t);
    if (!std::isfinite(w) || w < 0)
      return invalid_argument(std::string("recon settings: term_weights.") + term_name(t) +
                              " must be finite and >= 0, got " + std::to_string(w));
  }
  if (term_weight(Term::kPrimal) <= 0)
    return invalid_argument("recon settings: term_weights.primal must be > 0 (the primal anchors the solve)");
  GDVR_RETURN_IF_ERROR(at_least(l2_max_iterations, 1, "l2_max_iterations"));
  GDVR_RETURN_IF_ERROR(positive_finite(l2_tolerance, "l2_tolerance"));
  GDVR_RETURN_IF_ERROR(at_least(l1_outer_iterations, 1, "l1_outer_iterations"));
  GDVR_RETURN_IF_ERROR(at_least(l1_inner_iterations, 1, "l1_inner_iterations"));
  GDVR_RETURN_IF_ERROR(positive_finite(l1_inner_tolerance, "l1_inner_tolerance"));
  GDVR_RETURN_IF_ERROR(positive_finite(l1_epsilon0, "l1_epsilon0"));
  GDVR_RETURN_IF_ERROR(positive_finite(l1_epsilon_decay, "l1_epsilon_decay"));
  if (l1_epsilon_decay > 1) return invalid_argument("recon settings: l1_epsilon_decay must be <= 1");
  GDVR_RETURN_IF_ERROR(at_least(l1_denoised_outer_iterations, 1, "l1_denoised_outer_iterations"));
  GDVR_RETURN_IF_ERROR(positive_finite(l1_denoised_epsilon0, "l1_denoised_epsilon0"));
  GDVR_RETURN_IF_ERROR(positive_finite(l1_denoised_epsilon_decay, "l1_denoised_epsilon_decay"));
  if (l1_denoised_epsilon_decay > 1) return invalid_argument("recon settings: l1_denoised_epsilon_decay must be <= 1");
  GDVR_RETURN_IF_ERROR(at_least(cv_iterations, 0, "cv_iterations"));
  GDVR_RETURN_IF_ERROR(positive_finite(variance_floor, "variance_floor"));
  if (tile_size != 0 && tile_size < kMinReconTileSize)
    return invalid_argument("recon settings: tile_size must be 0 (no tiling) or >= " + std::to_string(kMinReconTileSize) +
                            ", got " + std::to_string(tile_size));
  GDVR_RETURN_IF_ERROR(at_least(tile_halo, 0, "tile_halo"));
  return Status::Ok();
}

std::string ReconSettings::to_string() const {
  std::ostringstream s;
  s << "method=" << recon_method_name(method) << " alpha=" << alpha << " term_weights={";
  for (Term t : kAllTerms) s << (t == Term::kPrimal ? "" : ",") << term_name(t) << ":" << term_weight(t);
  s << "} l2_max_iterations=" << l2_max_iterations << " l2_tolerance=" << l2_tolerance
    << " l1_outer_iterations=" << l1_outer_iterations << " l1_inner_iterations=" << l1_inner_iterations
    << " l1_inner_tolerance=" << l1_inner_tolerance << " l1_epsilon0=" << l1_epsilon0
    << " l1_epsilon_decay=" << l1_epsilon_decay << " l1_denoised_outer_iterations=" << l1_denoised_outer_iterations
    << " l1_denoised_epsilon0=" << l1_denoised_epsilon0 << " l1_denoised_epsilon_decay=" << l1_denoised_epsilon_decay
    << " l1_low_frequencies_from_primal=" << (l1_low_frequencies_from_primal ? "true" : "false")
    << " cv_iterations=" << cv_iterations
    << " variance_floor=" << variance_floor << " tile_size=" << tile_size << " tile_halo=" << tile_halo;
  return s.str();
}

}  // namespace gdvr
