#include "core/scene/gltf_loader.h"

namespace gdvr {

// Placeholder until the glTF loader lands (issue 4): a clear error, not a crash.
Expected<LoadedScene> load_gltf_scene(const std::string& path, const LoadOptions&) {
  return unimplemented("'" + path + "': glTF scenes are not supported yet");
}

}  // namespace gdvr
