// Loads a scene by file type: Mitsuba 3 XML (.xml) or glTF 2.0 (.gltf/.glb).
// A glTF file may carry its own animation, returned alongside the scene.
#pragma once

#include <string>

#include "core/scene/animation.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr {

struct LoadedScene {
  Scene scene;
  Animation animation;  // animation stored in the file itself (glTF); empty for XML
};

bool is_supported_scene_file(const std::string& path);
Expected<LoadedScene> load_scene(const std::string& path, const LoadOptions& options);

}  // namespace gdvr
