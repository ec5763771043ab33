// Atomic output files: writers produce "<path>.tmp.<pid>" and rename it over
// `path` only once it is complete, so a reader (the server streaming frames,
// a resumed job) never sees a half-written EXR, PNG or video.
#pragma once

#include <string>

#include "core/util/status.h"

namespace gdvr {

// "<path>.tmp.<pid>": same directory as `path`, so the rename stays within
// one file system and is atomic.
std::string temporary_path_for(const std::string& path);

// Renames `tmp` over `path`; on failure removes `tmp` and names both files.
Status commit_temporary(const std::string& tmp, const std::string& path);

// Best-effort removal of a temporary left by a failed write.
void discard_temporary(const std::string& tmp);

}  // namespace gdvr
