#include "core/scene/shape_tessellation.h"

#include <cmath>

namespace gdvr {

TriangleMesh make_rectangle_mesh() {
  TriangleMesh m;
  m.positions = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
  m.normals.assign(4, Vec3f(0, 0, 1));
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

TriangleMesh make_cube_mesh() {
  TriangleMesh m;
  // Mitsuba 3's cube: per face, its outward normal and its corners in the
  // order that carries uv (0, 1), (1, 1), (1, 0), (0, 0), as two triangles
  // (0, 1, 2), (3, 0, 2). The uv layout is what a texture on a cube shows.
  struct Face {
    Vec3f n;
    Vec3f corners[4];
  };
  const Face faces[6] = {
      {{0, -1, 0}, {{1, -1, -1}, {1, -1, 1}, {-1, -1, 1}, {-1, -1, -1}}},
      {{0, 1, 0}, {{1, 1, -1}, {-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}}},
      {{1, 0, 0}, {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}}},
      {{0, 0, 1}, {{1, -1, 1}, {1, 1, 1}, {-1, 1, 1}, {-1, -1, 1}}},
      {{-1, 0, 0}, {{-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}, {-1, -1, -1}}},
      {{0, 0, -1}, {{1, 1, -1}, {1, -1, -1}, {-1, -1, -1}, {-1, 1, -1}}},
  };
  const Vec2f uvs[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  for (const Face& f : faces) {
    const uint32_t base = uint32_t(m.positions.size());
    for (int i = 0; i < 4; ++i) {
      m.positions.push_back(f.corners[i]);
      m.normals.push_back(f.n);
      m.uvs.push_back(uvs[i]);
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base + 3, base, base + 2});
  }
  return m;
}

TriangleMesh make_disk_mesh(int segments) {
  if (segments < 3) segments = 3;
  TriangleMesh m;
  const float kTwoPi = 2.0f * kPi;
  for (int i = 0; i <= segments; ++i) {
    float v = float(i) / float(segments);
    float phi = v * kTwoPi;
    m.positions.push_back(Vec3f(std::cos(phi), std::sin(phi), 0));
    m.normals.push_back(Vec3f(0, 0, 1));
    m.uvs.push_back(Vec2f(1.0f, v));
  }
  for (int i = 0; i < segments; ++i) {
    uint32_t centre = uint32_t(m.positions.size());
    m.positions.push_back(Vec3f(0, 0, 0));
    m.normals.push_back(Vec3f(0, 0, 1));
    m.uvs.push_back(Vec2f(0.0f, (float(i) + 0.5f) / float(segments)));
    m.indices.insert(m.indices.end(), {centre, uint32_t(i), uint32_t(i + 1)});
  }
  return m;
}

}  // namespace gdvr
