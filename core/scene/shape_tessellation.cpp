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
  // Each face: its outward normal n and two in-plane axes (s, t) with s x t = n,
  // so that counter-clockwise corners seen from outside give outward winding.
  const Vec3f normals[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (const Vec3f& n : normals) {
    Vec3f s = std::abs(n.x) > 0 ? Vec3f(0, n.x, 0) : (std::abs(n.y) > 0 ? Vec3f(0, 0, n.y) : Vec3f(n.z, 0, 0));
    Vec3f t = cross(n, s);
    uint32_t base = uint32_t(m.positions.size());
    const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (const auto& c : corners) {
      m.positions.push_back(n + s * c[0] + t * c[1]);
      m.normals.push_back(n);
      m.uvs.push_back(Vec2f(0.5f * (c[0] + 1), 0.5f * (c[1] + 1)));
    }
    m.indices.insert(m.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
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
