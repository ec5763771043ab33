// The asset-root check: every file a scene, a job or a service request names
// must lie inside the folder it is confined to. One implementation, used by
// the scene loaders, the job runner and the server, so that they cannot
// disagree about "..", symlinks, trailing separators or look-alike prefixes.
#pragma once

#include <filesystem>

namespace gdvr {

// Whether `path` lies inside the folder `root` (or is `root`), comparing whole
// components after both are made absolute and resolved as far as they exist
// (std::filesystem::weakly_canonical: ".", ".." and symlinks), so that
// "root/../x" and a symlink out of root are outside, and "/srv/assets2" is not
// inside "/srv/assets". A path or root that cannot be resolved (empty, too
// long, an unreadable link) is "not inside": a check that cannot decide refuses.
bool is_inside_root(const std::filesystem::path& path, const std::filesystem::path& root);

}  // namespace gdvr
