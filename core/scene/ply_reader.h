// Stanford PLY meshes, ASCII and binary (little/big endian). Reads vertex
// x,y,z; nx,ny,nz; u,v (also s,t and texture_u,texture_v); and the face list
// vertex_indices (or vertex_index) of any integer type; polygons are
// fan-triangulated. Other elements and properties are skipped.
#pragma once

#include <string>

#include "core/scene/scene.h"
#include "core/util/status.h"

namespace gdvr {

Expected<TriangleMesh> read_ply(const std::string& path);
// `data` is the whole file; `origin` names it in error messages.
Expected<TriangleMesh> parse_ply(const std::string& data, const std::string& origin);

}  // namespace gdvr
