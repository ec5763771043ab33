#include "core/math/transform.h"

#include <cmath>
#include <sstream>

namespace gdvr {

Matrix4 Matrix4::identity() {
  Matrix4 r;
  for (int i = 0; i < 4; ++i) r.m[i][i] = 1.0;
  return r;
}

Matrix4 Matrix4::operator*(const Matrix4& o) const {
  Matrix4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += m[i][k] * o.m[k][j];
      r.m[i][j] = s;
    }
  return r;
}

Matrix4 Matrix4::transpose() const {
  Matrix4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) r.m[i][j] = m[j][i];
  return r;
}

bool Matrix4::is_finite() const {
  for (const auto& row : m)
    for (double v : row)
      if (!std::isfinite(v)) return false;
  return true;
}

// Gauss-Jordan elimination with partial pivoting.
bool Matrix4::inverse(Matrix4* out) const {
  if (!is_finite()) return false;
  double a[4][8];
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      a[i][j] = m[i][j];
      a[i][j + 4] = (i == j) ? 1.0 : 0.0;
    }
  double scale = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) scale = std::max(scale, std::abs(m[i][j]));
  if (scale == 0) return false;
  for (int col = 0; col < 4; ++col) {
    int pivot = col;
    for (int r = col + 1; r < 4; ++r)
      if (std::abs(a[r][col]) > std::abs(a[pivot][col])) pivot = r;
    if (std::abs(a[pivot][col]) <= 1e-300 || std::abs(a[pivot][col]) < scale * 1e-14) return false;
    if (pivot != col)
      for (int j = 0; j < 8; ++j) std::swap(a[col][j], a[pivot][j]);
    double inv_p = 1.0 / a[col][col];
    for (int j = 0; j < 8; ++j) a[col][j] *= inv_p;
    for (int r = 0; r < 4; ++r) {
      if (r == col) continue;
      double f = a[r][col];
      if (f == 0) continue;
      for (int j = 0; j < 8; ++j) a[r][j] -= f * a[col][j];
    }
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) out->m[i][j] = a[i][j + 4];
  return out->is_finite();
}

bool Transform::from_matrix(const Matrix4& m, Transform* out) {
  Matrix4 inv;
  if (!m.inverse(&inv)) return false;
  *out = Transform(m, inv);
  return true;
}

Transform Transform::translate(Vec3f d) {
  Matrix4 m = Matrix4::identity(), inv = Matrix4::identity();
  for (int i = 0; i < 3; ++i) {
    m.m[i][3] = d[i];
    inv.m[i][3] = -double(d[i]);
  }
  return Transform(m, inv);
}

Transform Transform::scale(Vec3f s) {
  Matrix4 m = Matrix4::identity(), inv = Matrix4::identity();
  for (int i = 0; i < 3; ++i) {
    m.m[i][i] = s[i];
    inv.m[i][i] = 1.0 / double(s[i]);
  }
  return Transform(m, inv);
}

Transform Transform::rotate(Vec3f axis_in, float angle_degrees) {
  double len = std::sqrt(double(axis_in.x) * axis_in.x + double(axis_in.y) * axis_in.y +
                         double(axis_in.z) * axis_in.z);
  if (len == 0) return Transform();
  double x = axis_in.x / len, y = axis_in.y / len, z = axis_in.z / len;
  double theta = double(angle_degrees) * M_PI / 180.0;
  double s = std::sin(theta), c = std::cos(theta), omc = 1 - c;
  Matrix4 m = Matrix4::identity();
  m.m[0][0] = x * x * omc + c;
  m.m[0][1] = x * y * omc - z * s;
  m.m[0][2] = x * z * omc + y * s;
  m.m[1][0] = y * x * omc + z * s;
  m.m[1][1] = y * y * omc + c;
  m.m[1][2] = y * z * omc - x * s;
  m.m[2][0] = z * x * omc - y * s;
  m.m[2][1] = z * y * omc + x * s;
  m.m[2][2] = z * z * omc + c;
  return Transform(m, m.transpose());  // rotation: inverse is the transpose
}

bool Transform::look_at(Vec3f origin, Vec3f target, Vec3f up, Transform* out) {
  double d[3] = {double(target.x) - origin.x, double(target.y) - origin.y, double(target.z) - origin.z};
  double dl = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(dl > 0)) return false;
  for (double& v : d) v /= dl;
  double u[3] = {up.x, up.y, up.z};
  // left = normalize(cross(up, dir)); Mitsuba 3 convention.
  double left[3] = {u[1] * d[2] - u[2] * d[1], u[2] * d[0] - u[0] * d[2], u[0] * d[1] - u[1] * d[0]};
  double ll = std::sqrt(left[0] * left[0] + left[1] * left[1] + left[2] * left[2]);
  if (!(ll > 1e-12)) return false;
  for (double& v : left) v /= ll;
  double new_up[3] = {d[1] * left[2] - d[2] * left[1], d[2] * left[0] - d[0] * left[2],
                      d[0] * left[1] - d[1] * left[0]};
  Matrix4 m = Matrix4::identity();
  double o[3] = {origin.x, origin.y, origin.z};
  for (int i = 0; i < 3; ++i) {
    m.m[i][0] = left[i];
    m.m[i][1] = new_up[i];
    m.m[i][2] = d[i];
    m.m[i][3] = o[i];
  }
  return from_matrix(m, out);
}

Transform Transform::operator*(const Transform& o) const { return Transform(m_ * o.m_, o.inv_ * inv_); }

Transform Transform::inverse() const { return Transform(inv_, m_); }

Vec3f Transform::point(Vec3f p) const {
  double r[4];
  for (int i = 0; i < 4; ++i) r[i] = m_.m[i][0] * p.x + m_.m[i][1] * p.y + m_.m[i][2] * p.z + m_.m[i][3];
  if (r[3] != 1.0 && r[3] != 0.0) {
    double inv_w = 1.0 / r[3];
    return Vec3f(float(r[0] * inv_w), float(r[1] * inv_w), float(r[2] * inv_w));
  }
  return Vec3f(float(r[0]), float(r[1]), float(r[2]));
}

Vec3f Transform::vector(Vec3f v) const {
  return Vec3f(float(m_.m[0][0] * v.x + m_.m[0][1] * v.y + m_.m[0][2] * v.z),
               float(m_.m[1][0] * v.x + m_.m[1][1] * v.y + m_.m[1][2] * v.z),
               float(m_.m[2][0] * v.x + m_.m[2][1] * v.y + m_.m[2][2] * v.z));
}

Vec3f Transform::normal(Vec3f n) const {
  return Vec3f(float(inv_.m[0][0] * n.x + inv_.m[1][0] * n.y + inv_.m[2][0] * n.z),
               float(inv_.m[0][1] * n.x + inv_.m[1][1] * n.y + inv_.m[2][1] * n.z),
               float(inv_.m[0][2] * n.x + inv_.m[1][2] * n.y + inv_.m[2][2] * n.z));
}

std::string Transform::to_string() const {
  std::ostringstream os;
  os << "[";
  for (int i = 0; i < 4; ++i) {
    os << (i ? "; " : "");
    for (int j = 0; j < 4; ++j) os << (j ? " " : "") << m_.m[i][j];
  }
  os << "]";
  return os.str();
}

}  // namespace gdvr
