#include "core/gradient/shape_motion.h"

#include <cmath>

namespace gdvr {
namespace {

double linear_determinant(const Matrix4& m4) {
  const auto& m = m4.m;
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

}  // namespace

ShapeMotion::ShapeMotion(const Scene& from, const Scene& to) {
  const size_t n = from.shapes.size();
  motion_.resize(n);
  identity_.assign(n, true);
  det_.assign(n, 1.0f);
  tangent_.assign(n, false);
  for (size_t i = 0; i < n && i < to.shapes.size(); ++i) {
    tangent_[i] = from.bsdfs[size_t(from.shapes[i].bsdf)].is_anisotropic();
    const Transform& a = from.shapes[i].to_world;
    const Transform& b = to.shapes[i].to_world;
    if (a == b) continue;  // static: the identity, exactly
    motion_[i] = b * a.inverse();
    identity_[i] = motion_[i].is_identity();
    det_[i] = float(std::abs(linear_determinant(motion_[i].matrix())));
  }
}

bool ShapeMotion::same(int a, int b) const {
  if (identity_[size_t(a)] && identity_[size_t(b)]) return true;
  return motion_[size_t(a)] == motion_[size_t(b)];
}

SurfaceInteraction ShapeMotion::carry(const SurfaceInteraction& si) const {
  if (identity_[size_t(si.shape)]) return si;
  const Transform& m = motion_[size_t(si.shape)];
  SurfaceInteraction out = si;
  out.p = m.point(si.p);
  out.n = normalize(m.normal(si.n));
  const Vec3f n = normalize(m.normal(si.sh_frame.n));
  // An anisotropic BSDF's tangent turns with its surface (FrameScene::interaction).
  out.sh_frame = tangent_[size_t(si.shape)] ? Frame::along_tangent(n, m.vector(si.sh_frame.s)) : Frame(n);
  return out;
}

float ShapeMotion::area_jacobian(const SurfaceInteraction& si) const {
  if (identity_[size_t(si.shape)]) return 1.0f;
  return det_[size_t(si.shape)] * length(motion_[size_t(si.shape)].normal(si.n));
}

}  // namespace gdvr
