#include "core/scene/gltf_animation.h"

#include <algorithm>
#include <cmath>

namespace gdvr {

namespace {

void normalize4(double* q) {
  double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 0)) {
    q[0] = q[1] = q[2] = 0;
    q[3] = 1;
    return;
  }
  for (int c = 0; c < 4; ++c) q[c] /= n;
}

// glTF 2.0 Appendix C: slerp(q_k, q_k+1, t) along the shorter arc. Near-equal
// quaternions fall back to a normalised lerp, where sin(a) ~ 0 would divide by ~0.
void slerp(const double* a, const double* b, double t, double* out) {
  double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  double s = d < 0 ? -1.0 : 1.0;
  double ad = std::min(1.0, std::abs(d));
  if (ad > 0.9999995) {
    for (int c = 0; c < 4; ++c) out[c] = (1 - t) * a[c] + t * s * b[c];
  } else {
    double angle = std::acos(ad);
    double sin_a = std::sin(angle);
    double wa = std::sin(angle * (1 - t)) / sin_a, wb = s * std::sin(angle * t) / sin_a;
    for (int c = 0; c < 4; ++c) out[c] = wa * a[c] + wb * b[c];
  }
  normalize4(out);
}

void trs_of(const GltfNode& n, std::array<double, 3>* t, std::array<double, 4>* r, std::array<double, 3>* s) {
  *t = n.translation;
  *r = n.rotation;
  *s = n.scale;
}

}  // namespace

void evaluate_gltf_sampler(const GltfSampler& sampler, double time, double* out) {
  const int nc = sampler.components;
  const size_t count = sampler.times.size();
  const bool cubic = sampler.interpolation == GltfInterpolation::kCubicSpline;
  // Offset of key k's value: cubic keys store (in-tangent, value, out-tangent).
  auto value = [&](size_t k) { return &sampler.values[cubic ? (3 * k + 1) * nc : k * nc]; };
  auto finish = [&] {
    if (nc == 4) normalize4(out);
  };
  if (count == 0) return;
  if (!(time > sampler.times.front()) || count == 1) {  // also NaN time: hold the first key
    std::copy(value(0), value(0) + nc, out);
    return finish();
  }
  if (time >= sampler.times.back()) {
    std::copy(value(count - 1), value(count - 1) + nc, out);
    return finish();
  }
  // Segment k with times[k] <= time < times[k + 1].
  size_t k = size_t(std::upper_bound(sampler.times.begin(), sampler.times.end(), time) - sampler.times.begin()) - 1;
  const double t0 = sampler.times[k], t1 = sampler.times[k + 1];
  const double td = t1 - t0;
  const double u = (time - t0) / td;
  const double* v0 = value(k);
  const double* v1 = value(k + 1);
  switch (sampler.interpolation) {
    case GltfInterpolation::kStep:
      std::copy(v0, v0 + nc, out);
      break;
    case GltfInterpolation::kLinear:
      if (nc == 4) {
        slerp(v0, v1, u, out);
      } else {
        for (int c = 0; c < nc; ++c) out[c] = (1 - u) * v0[c] + u * v1[c];
      }
      break;
    case GltfInterpolation::kCubicSpline: {
      // p(u) = (2u^3 - 3u^2 + 1) v_k + td (u^3 - 2u^2 + u) b_k
      //      + (-2u^3 + 3u^2) v_k+1 + td (u^3 - u^2) a_k+1
      // with b_k the out-tangent of key k and a_k+1 the in-tangent of key k+1.
      const double* b0 = &sampler.values[(3 * k + 2) * nc];
      const double* a1 = &sampler.values[(3 * (k + 1)) * nc];
      const double u2 = u * u, u3 = u2 * u;
      for (int c = 0; c < nc; ++c)
        out[c] = (2 * u3 - 3 * u2 + 1) * v0[c] + td * (u3 - 2 * u2 + u) * b0[c] + (-2 * u3 + 3 * u2) * v1[c] +
                 td * (u3 - u2) * a1[c];
      break;
    }
  }
  finish();
}

Matrix4 gltf_trs_matrix(const std::array<double, 3>& t, const std::array<double, 4>& r, const std::array<double, 3>& s) {
  const double x = r[0], y = r[1], z = r[2], w = r[3];
  const double rot[3][3] = {
      {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
      {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
      {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)},
  };
  Matrix4 m = Matrix4::identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m.m[i][j] = rot[i][j] * s[j];
    m.m[i][3] = t[i];
  }
  return m;
}

Matrix4 GltfNodeGraph::local_matrix(int node, double time) const {
  const GltfNode& n = nodes[size_t(node)];
  if (n.has_matrix) return n.matrix;  // the loader rejects animation of matrix nodes
  std::array<double, 3> t, s;
  std::array<double, 4> r;
  trs_of(n, &t, &r, &s);
  for (const GltfChannel& ch : channels) {
    if (ch.node != node) continue;
    switch (ch.path) {
      case GltfPath::kTranslation: evaluate_gltf_sampler(ch.sampler, time, t.data()); break;
      case GltfPath::kRotation: evaluate_gltf_sampler(ch.sampler, time, r.data()); break;
      case GltfPath::kScale: evaluate_gltf_sampler(ch.sampler, time, s.data()); break;
    }
  }
  // Static rotations are normalised too: exporters write them with float noise.
  normalize4(r.data());
  return gltf_trs_matrix(t, r, s);
}

Matrix4 GltfNodeGraph::world_matrix(int node, double time) const {
  Matrix4 m = local_matrix(node, time);
  for (int p = nodes[size_t(node)].parent; p >= 0; p = nodes[size_t(p)].parent) m = local_matrix(p, time) * m;
  return m;
}

bool GltfNodeGraph::is_animated(int node) const {
  for (int n = node; n >= 0; n = nodes[size_t(n)].parent)
    for (const GltfChannel& ch : channels)
      if (ch.node == n) return true;
  return false;
}

std::vector<double> GltfNodeGraph::key_times(int node) const {
  std::vector<double> times;
  for (int n = node; n >= 0; n = nodes[size_t(n)].parent)
    for (const GltfChannel& ch : channels)
      if (ch.node == n) times.insert(times.end(), ch.sampler.times.begin(), ch.sampler.times.end());
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

Transform gltf_to_transform(const Matrix4& m) {
  Transform out;
  if (Transform::from_matrix(m, &out)) return out;
  double largest = 0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) largest = std::max(largest, std::abs(m.m[i][j]));
  Matrix4 nudged = m;
  for (int i = 0; i < 3; ++i) nudged.m[i][i] += 1e-6 * (1 + largest);
  if (Transform::from_matrix(nudged, &out)) return out;
  Matrix4 tiny = Matrix4::identity();
  for (int i = 0; i < 3; ++i) {
    tiny.m[i][i] = 1e-6;
    tiny.m[i][3] = std::isfinite(m.m[i][3]) ? m.m[i][3] : 0.0;
  }
  Transform::from_matrix(tiny, &out);
  return out;
}

Matrix4 gltf_remove_scale(const Matrix4& m) {
  double c[3][3];  // c[j] = column j
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) c[j][i] = m.m[i][j];
  auto normalize3 = [](double* v) {
    double l = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0)
      for (int i = 0; i < 3; ++i) v[i] /= l;
  };
  normalize3(c[0]);
  double d = c[1][0] * c[0][0] + c[1][1] * c[0][1] + c[1][2] * c[0][2];
  for (int i = 0; i < 3; ++i) c[1][i] -= d * c[0][i];
  normalize3(c[1]);
  // z = x cross y keeps the frame right-handed even if the node mirrors.
  c[2][0] = c[0][1] * c[1][2] - c[0][2] * c[1][1];
  c[2][1] = c[0][2] * c[1][0] - c[0][0] * c[1][2];
  c[2][2] = c[0][0] * c[1][1] - c[0][1] * c[1][0];
  Matrix4 r = m;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) r.m[i][j] = c[j][i];
  return r;
}

Transform GltfNodeCurve::evaluate(double time) const {
  Matrix4 world = graph_->world_matrix(node_, time);
  return gltf_to_transform((rigid_ ? gltf_remove_scale(world) : world) * offset_);
}

}  // namespace gdvr
