#include "core/temporal/tgpt_settings.h"

#include <sstream>

namespace gdvr {

Status TgptSettings::validate() const {
  GDVR_RETURN_IF_ERROR(gpt.validate().with_context("tgpt.gpt: "));
  GDVR_RETURN_IF_ERROR(recon.validate().with_context("tgpt.recon: "));
  if (window < 1) return invalid_argument("tgpt.window must be at least 1 (got " + std::to_string(window) + ")");
  if (hop < 0 || hop > window)
    return invalid_argument("tgpt.hop must be between 0 (= window/2) and window (got " + std::to_string(hop) + ")");
  if (consistency_tolerance_px < 0) return invalid_argument("tgpt.consistency_tolerance_px must not be negative");
  return Status::Ok();
}

std::string TgptSettings::to_string() const {
  std::ostringstream s;
  s << "tgpt{temporal_shift=" << temporal_shift_name(temporal_shift) << " data_term=" << data_term_name(data_term)
    << " window=" << window << " hop=" << effective_hop() << " motion_vectors=" << (motion_vectors ? "on" : "off")
    << " motion_compensation=" << (motion_compensation ? "on" : "off")
    << " consistency_px=" << consistency_tolerance_px << " max_same_pixel_motion_px=" << max_same_pixel_motion_px
    << " gpt=" << gpt.to_string() << " recon=" << recon.to_string() << "}";
  return s.str();
}

}  // namespace gdvr
