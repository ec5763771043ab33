#include "core/scene/ply_reader.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

namespace gdvr {
namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

bool parse_ply_type(const std::string& s, PlyType* t) {
  static const struct { const char* name; PlyType type; } kTypes[] = {
      {"char", PlyType::kInt8},     {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},   {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16}, {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},   {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32}, {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& e : kTypes)
    if (s == e.name) {
      *t = e.type;
      return true;
    }
  return false;
}

size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::kInt8: case PlyType::kUint8: return 1;
    case PlyType::kInt16: case PlyType::kUint16: return 2;
    case PlyType::kInt32: case PlyType::kUint32: case PlyType::kFloat32: return 4;
    case PlyType::kFloat64: return 8;
  }
  return 1;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> props;
};

enum class PlyFormat { kAscii, kBinaryLittle, kBinaryBig };

// Reads scalar values in the file's encoding, tracking the position for errors.
class PlyValueReader {
 public:
  PlyValueReader(const std::string& data, size_t pos, PlyFormat format) : data_(data), pos_(pos), format_(format) {}

  bool read(PlyType t, double* out) {
    if (format_ == PlyFormat::kAscii) {
      while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
      if (pos_ >= data_.size()) return false;
      const char* begin = data_.c_str() + pos_;
      char* end = nullptr;
      *out = std::strtod(begin, &end);
      if (end == begin) return false;
      pos_ += size_t(end - begin);
      return true;
    }
    size_t n = type_size(t);
    if (pos_ + n > data_.size()) return false;
    unsigned char bytes[8];
    std::memcpy(bytes, data_.data() + pos_, n);
    pos_ += n;
    bool little_host = is_little_endian_host();
    if ((format_ == PlyFormat::kBinaryLittle) != little_host)
      for (size_t i = 0; i < n / 2; ++i) std::swap(bytes[i], bytes[n - 1 - i]);
    switch (t) {
      case PlyType::kInt8: { int8_t v; std::memcpy(&v, bytes, 1); *out = v; break; }
      case PlyType::kUint8: { uint8_t v; std::memcpy(&v, bytes, 1); *out = v; break; }
      case PlyType::kInt16: { int16_t v; std::memcpy(&v, bytes, 2); *out = v; break; }
      case PlyType::kUint16: { uint16_t v; std::memcpy(&v, bytes, 2); *out = v; break; }
      case PlyType::kInt32: { int32_t v; std::memcpy(&v, bytes, 4); *out = v; break; }
      case PlyType::kUint32: { uint32_t v; std::memcpy(&v, bytes, 4); *out = v; break; }
      case PlyType::kFloat32: { float v; std::memcpy(&v, bytes, 4); *out = v; break; }
      case PlyType::kFloat64: { double v; std::memcpy(&v, bytes, 8); *out = v; break; }
    }
    return true;
  }
  size_t pos() const { return pos_; }

 private:
  static bool is_little_endian_host() {
    uint16_t one = 1;
    unsigned char c;
    std::memcpy(&c, &one, 1);
    return c == 1;
  }
  const std::string& data_;
  size_t pos_;
  PlyFormat format_;
};

}  // namespace

Expected<TriangleMesh> read_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(path + ": cannot open PLY file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_ply(ss.str(), path);
}

Expected<TriangleMesh> parse_ply(const std::string& data, const std::string& origin) {
  // ---- Header ----
  size_t pos = 0;
  int line_no = 0;
  auto error = [&](const std::string& msg) { return invalid_argument(origin + ":" + std::to_string(line_no) + ": " + msg); };
  auto next_line = [&](std::string* line) {
    if (pos >= data.size()) return false;
    size_t end = data.find('\n', pos);
    if (end == std::string::npos) end = data.size();
    *line = data.substr(pos, end - pos);
    if (!line->empty() && line->back() == '\r') line->pop_back();
    pos = end + 1;
    ++line_no;
    return true;
  };
  std::string line;
  if (!next_line(&line) || line != "ply") return error("not a PLY file (missing 'ply' magic)");
  PlyFormat format = PlyFormat::kAscii;
  bool have_format = false, have_end = false;
  std::vector<PlyElement> elements;
  while (next_line(&line)) {
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    if (kw.empty() || kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") {
      std::string f, version;
      ls >> f >> version;
      if (f == "ascii") format = PlyFormat::kAscii;
      else if (f == "binary_little_endian") format = PlyFormat::kBinaryLittle;
      else if (f == "binary_big_endian") format = PlyFormat::kBinaryBig;
      else return error("unknown PLY format '" + f + "'");
      have_format = true;
    } else if (kw == "element") {
      PlyElement e;
      long long count = -1;
      ls >> e.name >> count;
      if (e.name.empty() || count < 0) return error("malformed element declaration");
      e.count = size_t(count);
      elements.push_back(e);
    } else if (kw == "property") {
      if (elements.empty()) return error("property before any element");
      PlyProperty p;
      std::string t;
      ls >> t;
      if (t == "list") {
        std::string ct, it;
        ls >> ct >> it >> p.name;
        p.is_list = true;
        if (!parse_ply_type(ct, &p.count_type) || !parse_ply_type(it, &p.type)) return error("unknown list property type");
      } else {
        ls >> p.name;
        if (!parse_ply_type(t, &p.type)) return error("unknown property type '" + t + "'");
      }
      if (p.name.empty()) return error("property without a name");
      elements.back().props.push_back(p);
    } else if (kw == "end_header") {
      have_end = true;
      break;
    } else {
      return error("unknown header keyword '" + kw + "'");
    }
  }
  if (!have_format || !have_end) return error("incomplete PLY header");

  // ---- Body ----
  TriangleMesh mesh;
  PlyValueReader reader(data, pos, format);
  auto body_error = [&](const std::string& msg) {
    return invalid_argument(origin + ": " + msg + " (byte " + std::to_string(reader.pos()) + ")");
  };
  bool vertices_seen = false;
  for (const PlyElement& e : elements) {
    // Every item takes at least one byte of the body (ASCII or binary), so a
    // count beyond the bytes left is corrupt; checked before a tiny file can
    // allocate or loop for a declared count of 2^63.
    if (e.count > data.size() - std::min(data.size(), reader.pos()))
      return body_error("element '" + e.name + "' declares " + std::to_string(e.count) + " items, more than the file holds");
    if (e.name == "vertex") {
      if (e.count > (size_t(1) << 31)) return body_error("too many vertices");
      int ix[3] = {-1, -1, -1}, in[3] = {-1, -1, -1}, iuv[2] = {-1, -1};
      for (size_t k = 0; k < e.props.size(); ++k) {
        const std::string& n = e.props[k].name;
        if (e.props[k].is_list) continue;
        if (n == "x") ix[0] = int(k); else if (n == "y") ix[1] = int(k); else if (n == "z") ix[2] = int(k);
        else if (n == "nx") in[0] = int(k); else if (n == "ny") in[1] = int(k); else if (n == "nz") in[2] = int(k);
        else if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") iuv[0] = int(k);
        else if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") iuv[1] = int(k);
      }
      if (ix[0] < 0 || ix[1] < 0 || ix[2] < 0) return body_error("vertex element lacks x, y or z");
      bool has_n = in[0] >= 0 && in[1] >= 0 && in[2] >= 0, has_uv = iuv[0] >= 0 && iuv[1] >= 0;
      mesh.positions.resize(e.count);
      if (has_n) mesh.normals.resize(e.count);
      if (has_uv) mesh.uvs.resize(e.count);
      std::vector<double> vals(e.props.size());
      for (size_t i = 0; i < e.count; ++i) {
        for (size_t k = 0; k < e.props.size(); ++k) {
          const PlyProperty& p = e.props[k];
          if (p.is_list) {
            double cnt = 0;
            if (!reader.read(p.count_type, &cnt)) return body_error("truncated vertex data");
            if (!(cnt >= 0 && cnt <= 1e9)) return body_error("implausible list length in the vertex element");
            double dummy;
            for (long j = 0; j < long(cnt); ++j)
              if (!reader.read(p.type, &dummy)) return body_error("truncated vertex data");
            continue;
          }
          if (!reader.read(p.type, &vals[k])) return body_error("truncated vertex data");
        }
        mesh.positions[i] = Vec3f(float(vals[ix[0]]), float(vals[ix[1]]), float(vals[ix[2]]));
        if (has_n) mesh.normals[i] = Vec3f(float(vals[in[0]]), float(vals[in[1]]), float(vals[in[2]]));
        if (has_uv) mesh.uvs[i] = Vec2f(float(vals[iuv[0]]), float(vals[iuv[1]]));
      }
      vertices_seen = true;
    } else if (e.name == "face") {
      int list_k = -1;
      for (size_t k = 0; k < e.props.size(); ++k)
        if (e.props[k].is_list && (e.props[k].name == "vertex_indices" || e.props[k].name == "vertex_index")) list_k = int(k);
      if (list_k < 0) return body_error("face element lacks a vertex_indices list");
      std::vector<uint32_t> poly;
      for (size_t i = 0; i < e.count; ++i) {
        for (size_t k = 0; k < e.props.size(); ++k) {
          const PlyProperty& p = e.props[k];
          double cnt = 1;
          if (p.is_list && !reader.read(p.count_type, &cnt)) return body_error("truncated face data");
          if (!(cnt >= 0 && cnt <= 1e6)) return body_error("implausible face vertex count");  // NaN too
          poly.clear();
          for (long j = 0; j < long(cnt); ++j) {
            double v = 0;
            if (!reader.read(p.type, &v)) return body_error("truncated face data");
            if (int(k) == list_k) {
              if (!(v >= 0 && v < 4294967295.0)) return body_error("negative, huge or NaN vertex index");
              poly.push_back(uint32_t(v));
            }
          }
          if (int(k) != list_k) continue;
          if (poly.size() < 3) return body_error("face " + std::to_string(i) + " has fewer than 3 vertices");
          for (size_t j = 1; j + 1 < poly.size(); ++j) mesh.indices.insert(mesh.indices.end(), {poly[0], poly[j], poly[j + 1]});
        }
      }
    } else {
      // Skip elements gdvr does not use (edges, materials, ...) value by value.
      for (size_t i = 0; i < e.count; ++i)
        for (const PlyProperty& p : e.props) {
          double cnt = 1, dummy;
          if (p.is_list && !reader.read(p.count_type, &cnt)) return body_error("truncated element '" + e.name + "'");
          // A float list count (or NaN) beyond long's range made long(cnt) undefined.
          if (!(cnt >= 0 && cnt <= 1e9)) return body_error("implausible list length in element '" + e.name + "'");
          for (long j = 0; j < long(cnt); ++j)
            if (!reader.read(p.type, &dummy)) return body_error("truncated element '" + e.name + "'");
        }
    }
  }
  if (!vertices_seen) return body_error("no vertex element");
  return mesh;
}

}  // namespace gdvr
