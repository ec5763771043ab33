#include "core/scene/obj_reader.h"

#include <cstdlib>
#include <fstream>
#include <unordered_map>
#include <vector>

namespace gdvr {
namespace {

struct ObjCorner {
  long v = 0, vt = 0, vn = 0;  // 1-based after resolution; 0 = absent
  bool operator==(const ObjCorner& o) const { return v == o.v && vt == o.vt && vn == o.vn; }
};
struct ObjCornerHash {
  size_t operator()(const ObjCorner& c) const {
    return std::hash<long>()(c.v) ^ (std::hash<long>()(c.vt) * 31) ^ (std::hash<long>()(c.vn) * 1000003);
  }
};

bool parse_float_token(const char*& p, float* out) {
  while (*p == ' ' || *p == '\t') ++p;
  char* end = nullptr;
  *out = std::strtof(p, &end);
  if (end == p) return false;
  p = end;
  return true;
}

// Turns a 1-based or negative (relative) OBJ index into a 1-based index; 0 on error.
long resolve_index(long idx, size_t count) {
  if (idx > 0) return idx <= long(count) ? idx : 0;
  if (idx < 0) return long(count) + idx + 1 > 0 ? long(count) + idx + 1 : 0;
  return 0;
}

}  // namespace

Expected<TriangleMesh> read_obj(const std::string& path, const ObjOptions& options) {
  std::ifstream in(path);
  if (!in) return not_found(path + ": cannot open OBJ file");
  return parse_obj(in, path, options);
}

Expected<TriangleMesh> parse_obj(std::istream& in, const std::string& origin, const ObjOptions& options) {
  std::vector<Vec3f> v, vn;
  std::vector<Vec2f> vt;
  std::vector<ObjCorner> corners;  // unique (v, vt, vn) combinations, in order of first use
  std::unordered_map<ObjCorner, uint32_t, ObjCornerHash> corner_index;
  std::vector<uint32_t> indices;
  bool any_vt = false, any_vn = false;

  std::string line;
  int line_no = 0;
  auto error = [&](const std::string& msg) { return invalid_argument(origin + ":" + std::to_string(line_no) + ": " + msg); };
  std::vector<uint32_t> face;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const char* p = line.c_str();
    while (*p == ' ' || *p == '\t') ++p;
    if (*p == '\0' || *p == '#') continue;
    if (p[0] == 'v' && (p[1] == ' ' || p[1] == '\t')) {
      p += 1;
      Vec3f x;
      for (int k = 0; k < 3; ++k)
        if (!parse_float_token(p, &x[k])) return error("malformed vertex position");
      v.push_back(x);
    } else if (p[0] == 'v' && p[1] == 't' && (p[2] == ' ' || p[2] == '\t')) {
      p += 2;
      Vec2f uv;
      if (!parse_float_token(p, &uv.x)) return error("malformed texture coordinate");
      if (!parse_float_token(p, &uv.y)) uv.y = 0;  // 1D texture coordinates are legal OBJ
      if (options.flip_tex_coords) uv.y = 1.0f - uv.y;
      vt.push_back(uv);
    } else if (p[0] == 'v' && p[1] == 'n' && (p[2] == ' ' || p[2] == '\t')) {
      p += 2;
      Vec3f x;
      for (int k = 0; k < 3; ++k)
        if (!parse_float_token(p, &x[k])) return error("malformed vertex normal");
      vn.push_back(x);
    } else if (p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) {
      p += 1;
      face.clear();
      while (true) {
        while (*p == ' ' || *p == '\t') ++p;
        if (*p == '\0') break;
        long raw[3] = {0, 0, 0};
        for (int k = 0; k < 3; ++k) {
          if (k > 0) {
            if (*p != '/') break;
            ++p;
            if (*p == '/' || *p == ' ' || *p == '\t' || *p == '\0') continue;  // "v//vn" or "v/"
          }
          char* end = nullptr;
          raw[k] = std::strtol(p, &end, 10);
          if (end == p) return error("malformed face index");
          p = end;
        }
        if (*p != '\0' && *p != ' ' && *p != '\t') return error("malformed face index");
        ObjCorner c;
        c.v = resolve_index(raw[0], v.size());
        if (c.v == 0) return error("face references vertex " + std::to_string(raw[0]) + " which does not exist");
        if (raw[1] != 0) {
          c.vt = resolve_index(raw[1], vt.size());
          if (c.vt == 0) return error("face references texture coordinate " + std::to_string(raw[1]) + " which does not exist");
          any_vt = true;
        }
        if (raw[2] != 0) {
          c.vn = resolve_index(raw[2], vn.size());
          if (c.vn == 0) return error("face references normal " + std::to_string(raw[2]) + " which does not exist");
          any_vn = true;
        }
        auto [it, inserted] = corner_index.emplace(c, uint32_t(corners.size()));
        if (inserted) corners.push_back(c);
        face.push_back(it->second);
      }
      if (face.size() < 3) return error("face with fewer than 3 vertices");
      for (size_t k = 1; k + 1 < face.size(); ++k) indices.insert(indices.end(), {face[0], face[k], face[k + 1]});
    }
    // Other statements (o, g, s, usemtl, mtllib, l, p, ...) carry nothing gdvr uses.
  }
  if (in.bad()) return internal_error(origin + ": read error");

  TriangleMesh mesh;
  mesh.positions.reserve(corners.size());
  for (const ObjCorner& c : corners) mesh.positions.push_back(v[c.v - 1]);
  if (any_vt) {
    mesh.uvs.reserve(corners.size());
    for (const ObjCorner& c : corners) mesh.uvs.push_back(c.vt ? vt[c.vt - 1] : Vec2f(0, 0));
  }
  if (any_vn) {
    mesh.normals.reserve(corners.size());
    // A corner without a normal gets NaN so that the repair pass recomputes normals.
    for (const ObjCorner& c : corners) mesh.normals.push_back(c.vn ? vn[c.vn - 1] : Vec3f(NAN));
  }
  mesh.indices = std::move(indices);
  return mesh;
}

}  // namespace gdvr
