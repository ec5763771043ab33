// Mitsuba's analytic primitives that gdvr renders as triangle meshes, in
// object space, with Mitsuba's normals and uv layout.
#pragma once

#include "core/scene/scene.h"

namespace gdvr {

// [-1,1]^2 at z = 0, normal +z, uv [0,1]^2 (two triangles).
TriangleMesh make_rectangle_mesh();
// [-1,1]^3, 24 vertices (4 per face, so normals stay flat), 12 triangles,
// outward normals, uv [0,1]^2 on every face laid out as Mitsuba 3's cube.
TriangleMesh make_cube_mesh();
// Unit disk at z = 0, normal +z, as a fan of `segments` triangles. Mitsuba's
// disk is analytic with uv = (r, phi / 2pi); each segment gets its own centre
// vertex (at the segment's mid angle) so that the uv seam interpolates
// correctly. 256 segments keep the area within 0.01% of pi.
TriangleMesh make_disk_mesh(int segments = 256);

}  // namespace gdvr
