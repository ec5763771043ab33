// Keyframe interpolation of to_world transforms.
//
// Each key's matrix is decomposed as M = T * R * S: T the translation column,
// R a rotation (unit quaternion) and S a diagonal scale. R comes from the polar
// decomposition of the upper 3x3 block A = R * P (Higham's iteration
// R <- (R + R^-T) / 2), and S is the diagonal of P = R^T A. Shear (the
// off-diagonal part of P) cannot be interpolated this way and is dropped
// between keys; at a key the key's own matrix is returned unchanged, so sheared
// keys are still exact there. A mirroring key (det A < 0) is stored as a
// proper rotation with negated scales.
#include "core/scene/animation.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/util/echo_text.h"

namespace gdvr {

namespace {

struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};

double qdot(const Quat& a, const Quat& b) { return a.w * b.w + a.x * b.x + a.y * b.y + a.z * b.z; }

Quat qnormalize(Quat q) {
  double n = std::sqrt(qdot(q, q));
  if (!(n > 0)) return Quat();
  return {q.w / n, q.x / n, q.y / n, q.z / n};
}

// Shoemake's conversion, picking the largest diagonal term for stability.
Quat quat_from_rotation(const double r[3][3]) {
  Quat q;
  double trace = r[0][0] + r[1][1] + r[2][2];
  if (trace > 0) {
    double s = std::sqrt(trace + 1.0) * 2;
    q.w = 0.25 * s;
    q.x = (r[2][1] - r[1][2]) / s;
    q.y = (r[0][2] - r[2][0]) / s;
    q.z = (r[1][0] - r[0][1]) / s;
  } else if (r[0][0] > r[1][1] && r[0][0] > r[2][2]) {
    double s = std::sqrt(1.0 + r[0][0] - r[1][1] - r[2][2]) * 2;
    q.w = (r[2][1] - r[1][2]) / s;
    q.x = 0.25 * s;
    q.y = (r[0][1] + r[1][0]) / s;
    q.z = (r[0][2] + r[2][0]) / s;
  } else if (r[1][1] > r[2][2]) {
    double s = std::sqrt(1.0 + r[1][1] - r[0][0] - r[2][2]) * 2;
    q.w = (r[0][2] - r[2][0]) / s;
    q.x = (r[0][1] + r[1][0]) / s;
    q.y = 0.25 * s;
    q.z = (r[1][2] + r[2][1]) / s;
  } else {
    double s = std::sqrt(1.0 + r[2][2] - r[0][0] - r[1][1]) * 2;
    q.w = (r[1][0] - r[0][1]) / s;
    q.x = (r[0][2] + r[2][0]) / s;
    q.y = (r[1][2] + r[2][1]) / s;
    q.z = 0.25 * s;
  }
  return qnormalize(q);
}

void rotation_from_quat(const Quat& q, double r[3][3]) {
  double w = q.w, x = q.x, y = q.y, z = q.z;
  r[0][0] = 1 - 2 * (y * y + z * z);
  r[0][1] = 2 * (x * y - w * z);
  r[0][2] = 2 * (x * z + w * y);
  r[1][0] = 2 * (x * y + w * z);
  r[1][1] = 1 - 2 * (x * x + z * z);
  r[1][2] = 2 * (y * z - w * x);
  r[2][0] = 2 * (x * z - w * y);
  r[2][1] = 2 * (y * z + w * x);
  r[2][2] = 1 - 2 * (x * x + y * y);
}

Quat slerp(Quat a, Quat b, double t) {
  double d = qdot(a, b);
  if (d < 0) {  // take the short way round
    b = {-b.w, -b.x, -b.y, -b.z};
    d = -d;
  }
  if (d > 0.9995) {  // nearly parallel: lerp avoids dividing by sin(theta) ~ 0
    return qnormalize({a.w + t * (b.w - a.w), a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z)});
  }
  double theta = std::acos(d);
  double s = std::sin(theta);
  double wa = std::sin((1 - t) * theta) / s, wb = std::sin(t * theta) / s;
  return {wa * a.w + wb * b.w, wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z};
}

double det3(const double a[3][3]) {
  return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
         a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
}

struct Decomposed {
  double t[3] = {0, 0, 0};
  Quat r;
  double s[3] = {1, 1, 1};
};

Decomposed decompose(const Matrix4& m) {
  Decomposed d;
  double a[3][3];
  for (int i = 0; i < 3; ++i) {
    d.t[i] = m.m[i][3];
    for (int j = 0; j < 3; ++j) a[i][j] = m.m[i][j];
  }
  double sign = det3(a) < 0 ? -1.0 : 1.0;
  // Polar decomposition of sign * A (proper rotation part).
  double r[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[i][j] = sign * a[i][j];
  for (int iter = 0; iter < 64; ++iter) {
    double det = det3(r);
    if (!(std::abs(det) > 1e-300)) break;
    double inv_t[3][3];  // (R^-1)^T = cofactor matrix / det
    inv_t[0][0] = (r[1][1] * r[2][2] - r[1][2] * r[2][1]) / det;
    inv_t[0][1] = (r[1][2] * r[2][0] - r[1][0] * r[2][2]) / det;
    inv_t[0][2] = (r[1][0] * r[2][1] - r[1][1] * r[2][0]) / det;
    inv_t[1][0] = (r[0][2] * r[2][1] - r[0][1] * r[2][2]) / det;
    inv_t[1][1] = (r[0][0] * r[2][2] - r[0][2] * r[2][0]) / det;
    inv_t[1][2] = (r[0][1] * r[2][0] - r[0][0] * r[2][1]) / det;
    inv_t[2][0] = (r[0][1] * r[1][2] - r[0][2] * r[1][1]) / det;
    inv_t[2][1] = (r[0][2] * r[1][0] - r[0][0] * r[1][2]) / det;
    inv_t[2][2] = (r[0][0] * r[1][1] - r[0][1] * r[1][0]) / det;
    double change = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double nv = 0.5 * (r[i][j] + inv_t[i][j]);
        change = std::max(change, std::abs(nv - r[i][j]));
        r[i][j] = nv;
      }
    if (change < 1e-15) break;
  }
  d.r = quat_from_rotation(r);
  // S = diag(R^T A); sign folds the mirror into the scales.
  for (int k = 0; k < 3; ++k) {
    double s = 0;
    for (int i = 0; i < 3; ++i) s += r[i][k] * a[i][k];
    d.s[k] = s;
  }
  return d;
}

Matrix4 compose(const Decomposed& d) {
  double r[3][3];
  rotation_from_quat(d.r, r);
  Matrix4 m = Matrix4::identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m.m[i][j] = r[i][j] * d.s[j];
    m.m[i][3] = d.t[i];
  }
  return m;
}

// Hermite basis on [0, 1] with tangents already scaled to the segment length.
double hermite(double p0, double m0, double p1, double m1, double u) {
  double u2 = u * u, u3 = u2 * u;
  return (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * m1;
}

}  // namespace

Transform evaluate_track(const Track& track, double time) {
  if (track.curve) return track.curve->evaluate(time);
  const std::vector<Keyframe>& keys = track.keys;
  if (keys.empty()) return Transform();
  if (!(time > keys.front().time)) return keys.front().to_world;  // also catches NaN time
  if (time >= keys.back().time) return keys.back().to_world;
  size_t i = 0;
  while (i + 1 < keys.size() && keys[i + 1].time <= time) ++i;
  const Keyframe& k0 = keys[i];
  const Keyframe& k1 = keys[i + 1];
  if (time == k0.time) return k0.to_world;
  if (track.interpolation == Interpolation::kStep) return k0.to_world;

  double h = k1.time - k0.time;
  double u = (time - k0.time) / h;
  Decomposed a = decompose(k0.to_world.matrix()), b = decompose(k1.to_world.matrix()), out;
  out.r = slerp(a.r, b.r, u);
  if (track.interpolation == Interpolation::kLinear) {
    for (int c = 0; c < 3; ++c) {
      out.t[c] = a.t[c] + u * (b.t[c] - a.t[c]);
      out.s[c] = a.s[c] + u * (b.s[c] - a.s[c]);
    }
  } else {
    // Catmull-Rom on translation and scale with non-uniform key spacing:
    // tangent at key k = (p[k+1] - p[k-1]) / (t[k+1] - t[k-1]); one-sided at the ends.
    Decomposed prev = i > 0 ? decompose(keys[i - 1].to_world.matrix()) : a;
    Decomposed next = i + 2 < keys.size() ? decompose(keys[i + 2].to_world.matrix()) : b;
    double t_prev = i > 0 ? keys[i - 1].time : k0.time;
    double t_next = i + 2 < keys.size() ? keys[i + 2].time : k1.time;
    auto tangent = [](double p_before, double p_after, double dt) { return dt > 0 ? (p_after - p_before) / dt : 0.0; };
    for (int c = 0; c < 3; ++c) {
      double m0 = tangent(prev.t[c], b.t[c], k1.time - t_prev) * h;
      double m1 = tangent(a.t[c], next.t[c], t_next - k0.time) * h;
      out.t[c] = hermite(a.t[c], m0, b.t[c], m1, u);
      double n0 = tangent(prev.s[c], b.s[c], k1.time - t_prev) * h;
      double n1 = tangent(a.s[c], next.s[c], t_next - k0.time) * h;
      out.s[c] = hermite(a.s[c], n0, b.s[c], n1, u);
    }
    // Rotation: slerp (above). Squad would smooth the angular velocity at keys,
    // but slerp never overshoots, which matters more for camera paths.
  }
  Transform t;
  if (!Transform::from_matrix(compose(out), &t)) {
    // A scale crossing zero (mirroring keys) has no valid in-between; hold the nearer key.
    return u < 0.5 ? k0.to_world : k1.to_world;
  }
  return t;
}

Status validate_animation(const Animation& anim, const Scene& scene) {
  std::set<std::string> ids;
  for (const Shape& s : scene.shapes)
    if (!s.id.empty()) ids.insert(s.id);
  for (const Emitter& e : scene.emitters)
    if (!e.id.empty()) ids.insert(e.id);
  if (!scene.camera.id.empty()) ids.insert(scene.camera.id);
  for (size_t ti = 0; ti < anim.tracks.size(); ++ti) {
    const Track& tr = anim.tracks[ti];
    std::string where = "tracks[" + std::to_string(ti) + "] (target '" + echo_text(tr.target) + "')";
    // A target the scene lacks is a bad argument of the job (NOT_FOUND is
    // kept for files and jobs that do not exist).
    if (tr.target != "sensor" && !ids.count(tr.target))
      return invalid_argument(where + ": no shape, emitter or sensor with this id in " + scene.source);
    if (tr.keys.empty()) return invalid_argument(where + ": no keyframes");
    for (size_t k = 0; k < tr.keys.size(); ++k) {
      if (!std::isfinite(tr.keys[k].time)) return invalid_argument(where + ": key " + std::to_string(k) + " has a non-finite time");
      if (!tr.keys[k].to_world.matrix().is_finite())
        return invalid_argument(where + ": key " + std::to_string(k) + " has a non-finite transform");
      if (k > 0 && !(tr.keys[k].time > tr.keys[k - 1].time))
        return invalid_argument(where + ": key times must be strictly increasing (key " + std::to_string(k) + ")");
    }
    for (size_t tj = 0; tj < ti; ++tj)
      if (anim.tracks[tj].target == tr.target) return invalid_argument(where + ": a second track for the same target");
  }
  return Status::Ok();
}

Status apply_animation(const Animation& anim, double time, Scene* scene) {
  GDVR_RETURN_IF_ERROR(validate_animation(anim, *scene));
  for (const Track& tr : anim.tracks) {
    Transform t = evaluate_track(tr, time);
    bool is_camera = tr.target == "sensor" || (!scene->camera.id.empty() && tr.target == scene->camera.id);
    if (is_camera) scene->camera.to_world = t;
    // A track replaces the whole to_world; for a sphere that includes its
    // centre and radius (the loader folded them into to_world).
    for (size_t i = 0; i < scene->shapes.size(); ++i) {
      Shape& s = scene->shapes[i];
      if (s.id != tr.target) continue;
      s.to_world = t;
      if (s.emitter >= 0 && size_t(s.emitter) < scene->emitters.size()) scene->emitters[s.emitter].to_world = t;
    }
    for (Emitter& e : scene->emitters)
      if (e.type != EmitterType::kArea && e.id == tr.target) e.to_world = t;
  }
  return Status::Ok();
}

}  // namespace gdvr
