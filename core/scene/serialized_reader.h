// Mitsuba's .serialized mesh container: several zlib-compressed meshes in one
// file, with a table of their offsets at the end.
//
// Layout (little endian): per mesh a uint16 magic 0x041C and a uint16 version
// (3 or 4), then a zlib stream holding uint32 flags, (version 4: a
// NUL-terminated name), uint64 vertex and triangle counts, positions, normals
// (flag 0x1), uvs (0x2), colours (0x8, skipped), all float (0x1000) or double
// (0x2000), and the indices (uint32, or uint64 beyond 2^32 vertices). The file
// ends with one offset per mesh (uint64 in version 4, uint32 in version 3) and
// the uint32 mesh count.
#pragma once

#include <string>

#include "core/scene/scene.h"
#include "core/util/status.h"

namespace gdvr {

Expected<TriangleMesh> read_serialized(const std::string& path, int shape_index);
// `data` is the whole file; `origin` names it in error messages.
Expected<TriangleMesh> parse_serialized(const std::string& data, int shape_index, const std::string& origin);

}  // namespace gdvr
