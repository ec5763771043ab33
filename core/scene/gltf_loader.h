// glTF 2.0 (.gltf/.glb) scenes with their node animation.
#pragma once

#include <string>

#include "core/scene/scene_loader.h"

namespace gdvr {

Expected<LoadedScene> load_gltf_scene(const std::string& path, const LoadOptions& options);

}  // namespace gdvr
