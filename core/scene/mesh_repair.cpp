#include "core/scene/mesh_repair.h"

#include <cmath>
#include <sstream>

namespace gdvr {

std::string MeshRepairReport::describe(const std::string& origin) const {
  std::ostringstream os;
  os << origin << ":";
  if (degenerate_triangles_dropped) os << " dropped " << degenerate_triangles_dropped << " degenerate triangle(s);";
  if (normals_repaired) os << " recomputed normals (" << normals_repaired << " non-finite or zero);";
  if (uvs_repaired) os << " zeroed " << uvs_repaired << " non-finite uv(s);";
  return os.str();
}

Status validate_and_repair_mesh(TriangleMesh* mesh, const std::string& origin, MeshRepairReport* report) {
  *report = MeshRepairReport();
  const size_t n = mesh->positions.size();
  if (mesh->indices.size() % 3 != 0) return invalid_argument(origin + ": index count is not a multiple of 3");
  if (!mesh->normals.empty() && mesh->normals.size() != n)
    return invalid_argument(origin + ": normal count differs from vertex count");
  if (!mesh->uvs.empty() && mesh->uvs.size() != n) return invalid_argument(origin + ": uv count differs from vertex count");
  for (size_t i = 0; i < n; ++i)
    if (!is_finite(mesh->positions[i]))
      return invalid_argument(origin + ": vertex " + std::to_string(i) + " has a non-finite position");

  // ---- Drop degenerate triangles (repeated vertices or zero area) ----
  std::vector<uint32_t> kept;
  kept.reserve(mesh->indices.size());
  for (size_t t = 0; t < mesh->indices.size(); t += 3) {
    uint32_t i0 = mesh->indices[t], i1 = mesh->indices[t + 1], i2 = mesh->indices[t + 2];
    if (i0 >= n || i1 >= n || i2 >= n)
      return invalid_argument(origin + ": triangle " + std::to_string(t / 3) + " indexes a vertex out of range");
    Vec3f c = cross(mesh->positions[i1] - mesh->positions[i0], mesh->positions[i2] - mesh->positions[i0]);
    float area2 = length_squared(c);
    if (i0 == i1 || i1 == i2 || i0 == i2 || !(area2 > 0.0f) || !std::isfinite(area2)) {
      ++report->degenerate_triangles_dropped;
      continue;
    }
    kept.insert(kept.end(), {i0, i1, i2});
  }
  mesh->indices.swap(kept);

  // ---- Normals: one bad normal means the exporter is not to be trusted; recompute all ----
  for (Vec3f& nrm : mesh->normals)
    if (!is_finite(nrm) || length_squared(nrm) == 0.0f) ++report->normals_repaired;
  if (report->normals_repaired) compute_vertex_normals(mesh);
  for (Vec3f& nrm : mesh->normals) nrm = normalize(nrm);

  for (Vec2f& uv : mesh->uvs)
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) {
      uv = Vec2f(0, 0);
      ++report->uvs_repaired;
    }
  return Status::Ok();
}

void compute_vertex_normals(TriangleMesh* mesh) {
  std::vector<Vec3f> acc(mesh->positions.size(), Vec3f(0.0f));
  for (size_t t = 0; t + 2 < mesh->indices.size(); t += 3) {
    uint32_t idx[3] = {mesh->indices[t], mesh->indices[t + 1], mesh->indices[t + 2]};
    Vec3f p[3] = {mesh->positions[idx[0]], mesh->positions[idx[1]], mesh->positions[idx[2]]};
    Vec3f fn = normalize(cross(p[1] - p[0], p[2] - p[0]));
    if (!is_finite(fn) || length_squared(fn) == 0.0f) continue;
    for (int k = 0; k < 3; ++k) {
      Vec3f e1 = normalize(p[(k + 1) % 3] - p[k]), e2 = normalize(p[(k + 2) % 3] - p[k]);
      float angle = std::acos(std::clamp(dot(e1, e2), -1.0f, 1.0f));
      acc[idx[k]] += fn * angle;
    }
  }
  for (Vec3f& a : acc) {
    a = normalize(a);
    // Isolated vertices get an arbitrary unit normal so that no NaN remains.
    if (!is_finite(a) || length_squared(a) == 0.0f) a = Vec3f(0, 0, 1);
  }
  mesh->normals.swap(acc);
}

}  // namespace gdvr
