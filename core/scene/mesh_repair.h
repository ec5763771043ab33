// Checks on mesh data from files: non-finite positions and out-of-range
// indices are errors; degenerate triangles are dropped; broken normals and uvs
// are repaired. A renderer must never see NaN geometry, but a scene exported
// with one bad triangle should still render.
#pragma once

#include <string>
#include <vector>

#include "core/scene/scene.h"
#include "core/util/status.h"

namespace gdvr {

struct MeshRepairReport {
  size_t degenerate_triangles_dropped = 0;
  size_t normals_repaired = 0;  // non-finite or zero normals (all normals were then recomputed)
  size_t uvs_repaired = 0;      // non-finite uvs set to (0, 0)
  bool changed() const { return degenerate_triangles_dropped || normals_repaired || uvs_repaired; }
  // One line for Scene::warnings, naming `origin`.
  std::string describe(const std::string& origin) const;
};

// Validates and repairs in place. `origin` names the mesh in error messages.
Status validate_and_repair_mesh(TriangleMesh* mesh, const std::string& origin, MeshRepairReport* report);

// Smooth vertex normals, each the angle-weighted mean of its faces' normals
// (as Mitsuba does for meshes whose file has none).
void compute_vertex_normals(TriangleMesh* mesh);

}  // namespace gdvr
