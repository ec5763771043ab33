#include "core/io/color_transform.h"

#include <OpenColorIO/OpenColorIO.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>

namespace gdvr {

namespace OCIO = OCIO_NAMESPACE;

struct ColorTransform::Impl {
  OCIO::ConstConfigRcPtr config;
  OCIO::ConstCPUProcessorRcPtr cpu;
};

namespace {

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "'" : ", '") + n + "'";
  return out.empty() ? "(none)" : out;
}

Expected<OCIO::ConstConfigRcPtr> load_config(const std::string& path) {
  if (path.empty())
    return invalid_argument("no OCIO config given (set $OCIO or pass gdvr's data/ocio/config.ocio)");
  try {
    OCIO::ConstConfigRcPtr config = OCIO::Config::CreateFromFile(path.c_str());
    // validate() catches dangling role/view references at start-up rather
    // than at the first frame.
    config->validate();
    return config;
  } catch (const std::exception& e) {
    return invalid_argument("OCIO config '" + path + "': " + e.what());
  }
}

std::vector<std::string> displays_of(const OCIO::ConstConfigRcPtr& config) {
  std::vector<std::string> names;
  for (int i = 0; i < config->getNumDisplays(); ++i) names.emplace_back(config->getDisplay(i));
  return names;
}

std::vector<std::string> views_of(const OCIO::ConstConfigRcPtr& config, const std::string& display) {
  std::vector<std::string> names;
  for (int i = 0; i < config->getNumViews(display.c_str()); ++i)
    names.emplace_back(config->getView(display.c_str(), i));
  return names;
}

bool contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

std::string resolve_ocio_config_path(const std::string& shipped_config) {
  const char* env = std::getenv("OCIO");
  return (env && *env) ? std::string(env) : shipped_config;
}

ColorTransform::ColorTransform(ColorTransformOptions options, std::unique_ptr<Impl> impl)
    : options_(std::move(options)), impl_(std::move(impl)) {}
ColorTransform::ColorTransform(ColorTransform&&) noexcept = default;
ColorTransform& ColorTransform::operator=(ColorTransform&&) noexcept = default;
ColorTransform::~ColorTransform() = default;

Expected<ColorTransform> ColorTransform::create(const ColorTransformOptions& options) {
  Expected<OCIO::ConstConfigRcPtr> config = load_config(options.config_path);
  if (!config.ok()) return config.status();
  const OCIO::ConstConfigRcPtr& cfg = config.value();
  const std::string where = " in OCIO config '" + options.config_path + "'";

  // Checked by hand: OCIO's own exceptions say "not found" without listing
  // what would have worked.
  const std::vector<std::string> displays = displays_of(cfg);
  if (!contains(displays, options.display))
    return invalid_argument("unknown display '" + options.display + "'" + where +
                            "; available displays: " + join(displays));
  const std::vector<std::string> views = views_of(cfg, options.display);
  if (!contains(views, options.view))
    return invalid_argument("unknown view '" + options.view + "' for display '" +
                            options.display + "'" + where + "; available views: " + join(views));
  if (!cfg->getColorSpace(options.input_colorspace.c_str())) {
    std::vector<std::string> spaces;
    for (int i = 0; i < cfg->getNumColorSpaces(); ++i)
      spaces.emplace_back(cfg->getColorSpaceNameByIndex(i));
    return invalid_argument("unknown input colour space '" + options.input_colorspace + "'" +
                            where + "; available colour spaces: " + join(spaces));
  }

  try {
    OCIO::DisplayViewTransformRcPtr dvt = OCIO::DisplayViewTransform::Create();
    dvt->setSrc(options.input_colorspace.c_str());
    dvt->setDisplay(options.display.c_str());
    dvt->setView(options.view.c_str());
    OCIO::ConstProcessorRcPtr processor = cfg->getProcessor(dvt);
    auto impl = std::make_unique<Impl>();
    impl->config = cfg;
    impl->cpu = processor->getOptimizedCPUProcessor(OCIO::OPTIMIZATION_DEFAULT);
    return ColorTransform(options, std::move(impl));
  } catch (const std::exception& e) {
    return internal_error("OCIO display '" + options.display + "' / view '" + options.view + "'" +
                          where + ": " + e.what());
  }
}

Expected<Image> ColorTransform::apply(const Image& linear_rgb) const {
  if (linear_rgb.empty() || linear_rgb.channels() < 3)
    return invalid_argument("colour transform needs a non-empty image with >= 3 channels, got " +
                            std::to_string(linear_rgb.channels()));
  const int w = linear_rgb.width(), h = linear_rgb.height(), nc = linear_rgb.channels();
  Image out(w, h, 3);
  for (size_t i = 0; i < linear_rgb.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) {
      const float v = linear_rgb.data()[i * nc + c];
      // NaN/inf would propagate through the ACES curves and poison a whole
      // video block after chroma subsampling.
      out.data()[i * 3 + c] = std::isfinite(v) ? v : 0.0f;
    }

  try {
    // Row bands in parallel: the ACES output transform is a few hundred
    // flops per pixel, worth spreading for 1080p frames.
    constexpr int kRowsPerTask = 32;
    tbb::parallel_for(tbb::blocked_range<int>(0, h, kRowsPerTask),
                      [&](const tbb::blocked_range<int>& r) {
                        OCIO::PackedImageDesc desc(out.data().data() + size_t(r.begin()) * w * 3,
                                                   w, r.end() - r.begin(), 3);
                        impl_->cpu->apply(desc);
                      });
  } catch (const std::exception& e) {
    return internal_error("OCIO apply (view '" + options_.view + "'): " + e.what());
  }
  if (options_.clamp_output)
    for (float& v : out.data()) v = std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
  return out;
}

Expected<std::vector<std::string>> ColorTransform::list_displays(const std::string& config_path) {
  Expected<OCIO::ConstConfigRcPtr> config = load_config(config_path);
  if (!config.ok()) return config.status();
  return displays_of(config.value());
}

Expected<std::vector<std::string>> ColorTransform::list_views(const std::string& config_path,
                                                              const std::string& display) {
  Expected<OCIO::ConstConfigRcPtr> config = load_config(config_path);
  if (!config.ok()) return config.status();
  std::vector<std::string> displays = displays_of(config.value());
  if (!contains(displays, display))
    return invalid_argument("unknown display '" + display + "' in OCIO config '" + config_path +
                            "'; available displays: " + join(displays));
  return views_of(config.value(), display);
}

}  // namespace gdvr
