// Where a job's scene file lives. A scene named "uploads/<hash>/<file>" is an
// uploaded bundle (server/upload_store.h): it lies in the upload folder, and
// everything it references must lie inside its own bundle. Any other name is
// relative to the operator's asset root. Both are checked here before core
// reads a byte, so the status codes follow docs/service.md: a malformed name
// (NUL byte, a component over 255 bytes, not .xml/.gltf/.glb, outside its
// root) is INVALID_ARGUMENT, a well-formed one that is not there NOT_FOUND.
#pragma once

#include <string>

#include "core/util/status.h"
#include "server/config.h"

namespace gdvr::server {

struct SceneLocation {
  std::string root;         // the folder the scene and its files are confined to
  std::string relative;     // the scene, relative to root (what core's job names)
  std::string upload_hash;  // the bundle, for an uploaded scene; "" otherwise
};

// The prefix that names the upload folder in JobSpec.scene.
constexpr const char* kUploadScenePrefix = "uploads/";

Expected<SceneLocation> locate_scene(const ServerConfig& config, const std::string& scene);

// Whether `name` is a bundle folder name (64 lowercase hex digits).
bool is_bundle_hash(const std::string& name);

}  // namespace gdvr::server
