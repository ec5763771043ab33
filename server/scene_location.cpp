#include "server/scene_location.h"

#include <filesystem>

#include "core/scene/scene_loader.h"
#include "core/util/echo_text.h"
#include "core/util/path_confinement.h"

namespace gdvr::server {
namespace fs = std::filesystem;

namespace {

// Longest file name on the file systems the server runs on (NAME_MAX); a
// longer component cannot exist, and resolving it fails in ways that would
// otherwise read as "outside the root".
constexpr size_t kMaxComponentBytes = 255;

}  // namespace

bool is_bundle_hash(const std::string& name) {
  if (name.size() != 64) return false;
  for (char c : name)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}

Expected<SceneLocation> locate_scene(const ServerConfig& config, const std::string& scene) {
  const std::string shown = "scene: '" + echo_text(scene) + "'";
  if (scene.empty()) return invalid_argument("scene: missing (a .xml, .gltf or .glb path under the asset root)");
  if (scene.find('\0') != std::string::npos) return invalid_argument(shown + " contains a NUL byte");
  for (const auto& part : fs::path(scene))
    if (part.native().size() > kMaxComponentBytes)
      return invalid_argument(shown + " has a path component longer than " + std::to_string(kMaxComponentBytes) +
                              " bytes");
  SceneLocation loc;
  const std::string prefix = kUploadScenePrefix;
  if (scene.compare(0, prefix.size(), prefix) == 0) {
    std::string rest = scene.substr(prefix.size());
    size_t slash = rest.find('/');
    std::string hash = rest.substr(0, slash);
    if (slash == std::string::npos || !is_bundle_hash(hash))
      return invalid_argument(shown + " is not an uploaded bundle's scene (uploads/<64 hex digits>/<file>, as "
                                      "UploadScene returns it)");
    loc.upload_hash = hash;
    loc.root = (fs::path(config.uploads.root) / hash).string();
    loc.relative = rest.substr(slash + 1);
    if (!is_inside_root(fs::path(loc.root) / loc.relative, loc.root))
      return invalid_argument(shown + " is outside its upload bundle");
  } else {
    loc.root = config.asset_root;
    loc.relative = scene;
    fs::path p = fs::path(scene).is_absolute() ? fs::path(scene) : fs::path(config.asset_root) / scene;
    if (!is_inside_root(p, config.asset_root)) return invalid_argument(shown + " is outside the asset root");
  }
  if (!is_supported_scene_file(scene)) return invalid_argument(shown + " is not a .xml, .gltf or .glb scene");
  std::error_code ec;
  fs::path file = fs::path(loc.relative).is_absolute() ? fs::path(loc.relative) : fs::path(loc.root) / loc.relative;
  if (!fs::is_regular_file(file, ec)) return not_found(shown + " does not exist");
  return loc;
}

}  // namespace gdvr::server
