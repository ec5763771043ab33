// libFuzzer target: the glTF 2.0 loader (.gltf JSON or .glb, told apart by
// content). The loader reads files only, so each input goes to a private
// temporary folder, which is also the asset root: external buffers and images
// cannot leave it.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/scene/gltf_loader.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

// Created once per process, removed at exit. Leaked on purpose: the atexit
// handler must not outlive a static std::string it reads.
const std::string& temp_dir() {
  static const std::string* dir = [] {
    char tmpl[] = "/tmp/gdvr_fuzz_gltf_XXXXXX";
    const char* d = mkdtemp(tmpl);
    if (!d) std::abort();
    auto* s = new std::string(d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(temp_dir(), ec);
    });
    return s;
  }();
  return *dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > gdvr::fuzz::kMaxInput) return 0;
  const std::string path = temp_dir() + "/input.gltf";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  gdvr::LoadOptions options;
  options.asset_root = temp_dir();
  auto loaded = gdvr::load_gltf_scene(path, options);
  if (loaded.ok()) {
    for (const gdvr::Shape& s : loaded->scene.shapes) {
      gdvr::fuzz::check(s.bsdf >= 0 && size_t(s.bsdf) < loaded->scene.bsdfs.size(), "shape bsdf index valid");
      if (s.mesh) gdvr::fuzz::check_mesh(*s.mesh);
    }
  }
  return 0;
}
