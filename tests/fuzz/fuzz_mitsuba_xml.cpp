// libFuzzer target: the Mitsuba XML loader (from a string). Files the scene
// names resolve in tests/fuzz/assets, which is also the asset root, so the
// fuzzer cannot reach other files.
#include <string>

#include "core/scene/mitsuba_loader.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > gdvr::fuzz::kMaxInput) return 0;
  const std::string xml(reinterpret_cast<const char*>(data), size);
  gdvr::LoadOptions options;
  options.asset_root = GDVR_FUZZ_ASSETS;
  auto scene = gdvr::load_mitsuba_scene_from_string(xml, GDVR_FUZZ_ASSETS, options);
  if (scene.ok()) {
    for (const gdvr::Shape& s : scene->shapes) {
      gdvr::fuzz::check(s.bsdf >= 0 && size_t(s.bsdf) < scene->bsdfs.size(), "shape bsdf index valid");
      if (s.mesh) gdvr::fuzz::check_mesh(*s.mesh);
    }
  } else {
    gdvr::fuzz::check(!scene.status().message().empty(), "errors carry a message");
  }
  return 0;
}
