// Loader for the Mitsuba 3 XML subset gdvr supports (Mitsuba 0.x files are
// upgraded first, as Mitsuba 3 does: mitsuba_upgrade.h). Every error names the
// file, the line and the offending plugin/attribute; unknown attributes and
// plugins are errors, never silently ignored.
#pragma once

#include <map>
#include <string>

#include "core/scene/scene.h"
#include "core/util/status.h"

namespace gdvr {

struct LoadOptions {
  // Overrides of <default name=... value=...> (command-line -D / --param).
  std::map<std::string, std::string> params;
  // When non-empty, every file the scene references must resolve inside this
  // folder (the server's asset root); anything else is an error.
  std::string asset_root;
};

Expected<Scene> load_mitsuba_scene(const std::string& path, const LoadOptions& options);
Expected<Scene> load_mitsuba_scene_from_string(const std::string& xml, const std::string& base_dir,
                                               const LoadOptions& options);

}  // namespace gdvr
