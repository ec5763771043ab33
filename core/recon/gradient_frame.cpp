#include "core/recon/gradient_frame.h"

#include <cmath>

namespace gdvr {

Status GradientFrame::validate() const {
  const Image& primal = buffer(Term::kPrimal);
  if (primal.empty()) return invalid_argument("gradient frame: primal buffer is missing");
  if (primal.channels() < 1) return invalid_argument("gradient frame: primal has no channels");
  const auto check_shape = [&](const Image& img, const std::string& what) -> Status {
    if (img.empty()) return Status::Ok();
    if (img.width() != primal.width() || img.height() != primal.height() || img.channels() != primal.channels())
      return invalid_argument("gradient frame: buffer '" + what + "' is " + std::to_string(img.width()) + "x" +
                              std::to_string(img.height()) + "x" + std::to_string(img.channels()) +
                              ", primal is " + std::to_string(primal.width()) + "x" +
                              std::to_string(primal.height()) + "x" + std::to_string(primal.channels()));
    return Status::Ok();
  };
  if (!data_weight.empty() && (data_weight.width() != primal.width() || data_weight.height() != primal.height() ||
                               data_weight.channels() != 1))
    return invalid_argument("gradient frame: data weight is " + std::to_string(data_weight.width()) + "x" +
                            std::to_string(data_weight.height()) + "x" + std::to_string(data_weight.channels()) +
                            ", expected " + std::to_string(primal.width()) + "x" + std::to_string(primal.height()) +
                            "x1");
  if (!temporal_target.empty()) {
    if (temporal_target.width() != primal.width() || temporal_target.height() != primal.height() ||
        temporal_target.channels() != 2)
      return invalid_argument("gradient frame: temporal target is " + std::to_string(temporal_target.width()) + "x" +
                              std::to_string(temporal_target.height()) + "x" +
                              std::to_string(temporal_target.channels()) + ", expected " +
                              std::to_string(primal.width()) + "x" + std::to_string(primal.height()) + "x2");
    for (float v : temporal_target.data())
      if (!(std::fabs(v) <= 1e6f) || v != std::round(v))
        return invalid_argument("gradient frame: temporal target offsets must be whole pixels, found " +
                                std::to_string(v));
  }
  for (Term t : kAllTerms) {
    GDVR_RETURN_IF_ERROR(check_shape(buffer(t), term_name(t)));
    GDVR_RETURN_IF_ERROR(check_shape(variance(t), std::string(term_name(t)) + "_var"));
    if (!variance(t).empty() && !has(t))
      return invalid_argument(std::string("gradient frame: variance for missing buffer '") + term_name(t) + "'");
    if (!mask(t).empty() && mask(t).size() != primal.pixel_count())
      return invalid_argument(std::string("gradient frame: mask '") + term_name(t) + "' has " +
                              std::to_string(mask(t).size()) + " entries, expected " +
                              std::to_string(primal.pixel_count()));
  }
  return Status::Ok();
}

Expected<GradientFrame> gradient_frame_from_layers(const LayeredImage& layers) {
  GradientFrame frame;
  for (Term t : kAllTerms) {
    if (const ImageLayer* l = layers.find(term_name(t))) frame.buffer(t) = l->image;
    if (const ImageLayer* l = layers.find(std::string(term_name(t)) + "_var")) frame.variance(t) = l->image;
  }
  GDVR_RETURN_IF_ERROR(frame.validate());
  return frame;
}

}  // namespace gdvr
