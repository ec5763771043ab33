// Display transforms through OpenColorIO: the one place gdvr talks to OCIO.
// Renders are linear Rec.709; a ColorTransform turns them into display-encoded
// [0, 1] RGB (for PNG previews and the video encoder) with an OCIO
// display/view, by default ACES 1.0 SDR video on an sRGB display.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "core/util/status.h"

namespace gdvr {

struct ColorTransformOptions {
  // Path of an OCIO config; see resolve_ocio_config_path() for the default.
  std::string config_path;
  std::string display = "sRGB - Display";
  std::string view = "ACES 1.0 - SDR Video";
  // What the renderer's pixels are, named as in the ACES studio configs.
  std::string input_colorspace = "Linear Rec.709 (sRGB)";
  // Display encodings are [0, 1] by definition; tone curves and gamut
  // conversion can overshoot by rounding, which 8-bit/video quantisers must
  // not see. Off only to inspect the raw transform.
  bool clamp_output = true;
};

// The config to use: $OCIO when set and non-empty (the VFX-wide convention),
// otherwise `shipped_config` (gdvr's data/ocio/config.ocio, located by the
// caller, which knows where the data directory is installed).
std::string resolve_ocio_config_path(const std::string& shipped_config);

// An immutable, ready-to-apply display/view transform. The optimised OCIO CPU
// processor is built once at create() and reused by every apply(); apply() is
// const and safe to call from several threads.
class ColorTransform {
 public:
  // Loads and validates the config and builds the processor. Errors name the
  // config, display, view or colour space at fault and list the valid ones.
  static Expected<ColorTransform> create(const ColorTransformOptions& options);

  ColorTransform(ColorTransform&&) noexcept;
  ColorTransform& operator=(ColorTransform&&) noexcept;
  ~ColorTransform();

  // Returns a 3-channel display-encoded copy of the first three channels of
  // `linear_rgb` (which needs >= 3 channels). Non-finite inputs become 0.
  Expected<Image> apply(const Image& linear_rgb) const;

  const ColorTransformOptions& options() const { return options_; }

  // Names known to a config, for UIs and error messages.
  static Expected<std::vector<std::string>> list_displays(const std::string& config_path);
  static Expected<std::vector<std::string>> list_views(const std::string& config_path,
                                                        const std::string& display);

 private:
  struct Impl;
  ColorTransform(ColorTransformOptions options, std::unique_ptr<Impl> impl);

  ColorTransformOptions options_;
  std::unique_ptr<Impl> impl_;  // hides OCIO's headers from every includer
};

}  // namespace gdvr
