#include "core/scene/scene_loader.h"

#include <filesystem>

#include "core/scene/gltf_loader.h"

namespace gdvr {
namespace {

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

bool is_supported_scene_file(const std::string& path) {
  std::string ext = lower_extension(path);
  return ext == ".xml" || ext == ".gltf" || ext == ".glb";
}

Expected<LoadedScene> load_scene(const std::string& path, const LoadOptions& options) {
  std::string ext = lower_extension(path);
  if (ext == ".xml") {
    auto scene = load_mitsuba_scene(path, options);
    if (!scene.ok()) return scene.status();
    LoadedScene out;
    out.scene = std::move(scene.value());
    return out;
  }
  if (ext == ".gltf" || ext == ".glb") return load_gltf_scene(path, options);
  return unimplemented("'" + path + "': unsupported scene format (expected .xml, .gltf or .glb)");
}

}  // namespace gdvr
