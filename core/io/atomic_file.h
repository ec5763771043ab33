// Atomic output files: writers produce "<path>.tmp.<host>.<pid>" and rename it over
// `path` only once it is complete, so a reader (the server streaming frames,
// a resumed job) never sees a half-written EXR, PNG or video.
#pragma once

#include <string>

#include "core/util/status.h"

namespace gdvr {

// "<path>.tmp.<host>.<pid>": same directory as `path`, so the rename stays
// within one file system and is atomic; the host keeps two machines writing
// one frame on shared storage (a farm retry racing the attempt it replaces)
// from sharing a temporary.
std::string temporary_path_for(const std::string& path);

// Renames `tmp` over `path`; on failure removes `tmp` and names both files.
Status commit_temporary(const std::string& tmp, const std::string& path);

// Writes `text` to `path` through a temporary file.
Status write_text_atomic(const std::string& path, const std::string& text);

// Best-effort removal of a temporary left by a failed write.
void discard_temporary(const std::string& tmp);

// Removes the temporaries in `dir` whose writer was a process of this host
// that no longer runs (a worker killed mid-write). Temporaries of other hosts
// are left alone: on shared storage their writers may still be running.
void remove_temporaries_of_dead_writers(const std::string& dir);

// Reads a whole file; NOT_FOUND naming it when it cannot be read.
Expected<std::string> read_text_file(const std::string& path);

}  // namespace gdvr
