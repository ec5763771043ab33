#include "core/scene/serialized_reader.h"

#include <zlib.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <type_traits>
#include <vector>

namespace gdvr {
namespace {

constexpr uint16_t kSerializedMagic = 0x041C;
constexpr uint32_t kFlagNormals = 0x0001;
constexpr uint32_t kFlagTexcoords = 0x0002;
constexpr uint32_t kFlagColors = 0x0008;
constexpr uint32_t kFlagSinglePrecision = 0x1000;
constexpr uint32_t kFlagDoublePrecision = 0x2000;

// The format is little endian; assembling values byte by byte keeps the read
// independent of the host's byte order.
template <typename T>
T load_le(const unsigned char* p) {
  uint64_t v = 0;
  for (size_t i = 0; i < sizeof(T); ++i) v |= uint64_t(p[i]) << (8 * i);
  T out;
  if constexpr (sizeof(T) == 8) {
    std::memcpy(&out, &v, 8);
  } else {
    auto narrow = static_cast<std::conditional_t<sizeof(T) == 4, uint32_t, uint16_t>>(v);
    std::memcpy(&out, &narrow, sizeof(T));
  }
  return out;
}

// Inflates one zlib stream starting at `offset`; stops at the end of the stream.
Status inflate_stream(const std::string& data, size_t offset, std::string* out, const std::string& origin) {
  z_stream zs;
  std::memset(&zs, 0, sizeof(zs));
  if (inflateInit(&zs) != Z_OK) return internal_error(origin + ": zlib initialisation failed");
  zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data() + offset));
  zs.avail_in = uInt(data.size() - offset);
  char buf[1 << 16];
  int ret = Z_OK;
  while (ret != Z_STREAM_END) {
    zs.next_out = reinterpret_cast<Bytef*>(buf);
    zs.avail_out = sizeof(buf);
    ret = inflate(&zs, Z_NO_FLUSH);
    if (ret != Z_OK && ret != Z_STREAM_END) {
      inflateEnd(&zs);
      return invalid_argument(origin + ": corrupt compressed mesh data (zlib error " + std::to_string(ret) + ")");
    }
    out->append(buf, sizeof(buf) - zs.avail_out);
    if (ret == Z_OK && zs.avail_in == 0 && zs.avail_out != 0) {
      inflateEnd(&zs);
      return invalid_argument(origin + ": truncated compressed mesh data");
    }
    if (out->size() > (size_t(1) << 33)) {
      inflateEnd(&zs);
      return resource_exhausted(origin + ": mesh larger than 8 GiB");
    }
  }
  inflateEnd(&zs);
  return Status::Ok();
}

}  // namespace

Expected<TriangleMesh> read_serialized(const std::string& path, int shape_index) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return not_found(path + ": cannot open serialized mesh file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_serialized(ss.str(), shape_index, path);
}

Expected<TriangleMesh> parse_serialized(const std::string& data, int shape_index, const std::string& origin) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  if (data.size() < 8) return invalid_argument(origin + ": file too small to be a serialized mesh");
  if (load_le<uint16_t>(bytes) != kSerializedMagic) return invalid_argument(origin + ": not a Mitsuba serialized mesh (bad magic)");
  uint16_t version = load_le<uint16_t>(bytes + 2);
  if (version != 3 && version != 4) return invalid_argument(origin + ": unsupported serialized version " + std::to_string(version));

  // ---- Offset dictionary at the end of the file ----
  uint32_t count = load_le<uint32_t>(bytes + data.size() - 4);
  size_t entry = version == 4 ? 8 : 4;
  if (count == 0 || size_t(count) * entry + 4 > data.size())
    return invalid_argument(origin + ": corrupt mesh offset table (count " + std::to_string(count) + ")");
  if (shape_index < 0 || uint32_t(shape_index) >= count)
    return invalid_argument(origin + ": shape_index " + std::to_string(shape_index) + " out of range (file holds " +
                            std::to_string(count) + " meshes)");
  size_t table = data.size() - 4 - size_t(count) * entry;
  const unsigned char* e = bytes + table + size_t(shape_index) * entry;
  uint64_t offset = version == 4 ? load_le<uint64_t>(e) : load_le<uint32_t>(e);
  if (offset > table || table - offset < 4) return invalid_argument(origin + ": mesh offset beyond the data");  // no overflow for offsets near 2^64
  if (load_le<uint16_t>(bytes + offset) != kSerializedMagic || load_le<uint16_t>(bytes + offset + 2) != version)
    return invalid_argument(origin + ": mesh " + std::to_string(shape_index) + " has a bad header");

  std::string raw;
  GDVR_RETURN_IF_ERROR(inflate_stream(data, size_t(offset) + 4, &raw, origin));

  // ---- Mesh payload ----
  const auto* p = reinterpret_cast<const unsigned char*>(raw.data());
  size_t pos = 0;
  auto need = [&](size_t n) { return pos + n <= raw.size(); };
  auto truncated = [&]() { return invalid_argument(origin + ": mesh " + std::to_string(shape_index) + " is truncated"); };
  if (!need(4)) return truncated();
  uint32_t flags = load_le<uint32_t>(p);
  pos = 4;
  if (version == 4) {
    size_t nul = raw.find('\0', pos);
    if (nul == std::string::npos) return truncated();
    pos = nul + 1;
  }
  if (!need(16)) return truncated();
  uint64_t vertex_count = load_le<uint64_t>(p + pos), triangle_count = load_le<uint64_t>(p + pos + 8);
  pos += 16;
  bool dbl = (flags & kFlagDoublePrecision) != 0;
  if (dbl && (flags & kFlagSinglePrecision)) return invalid_argument(origin + ": both single and double precision flags set");
  size_t scalar = dbl ? 8 : 4;
  size_t index_size = vertex_count > 0xFFFFFFFFull ? 8 : 4;
  // Check sizes before allocating so that a corrupt header cannot ask for terabytes.
  size_t per_vertex = 3 * scalar + ((flags & kFlagNormals) ? 3 * scalar : 0) + ((flags & kFlagTexcoords) ? 2 * scalar : 0) +
                      ((flags & kFlagColors) ? 3 * scalar : 0);
  if (vertex_count > raw.size() || triangle_count > raw.size() ||
      pos + vertex_count * per_vertex + triangle_count * 3 * index_size > raw.size())
    return truncated();
  if (vertex_count > 0xFFFFFFFFull) return resource_exhausted(origin + ": more than 2^32 vertices");

  auto read_scalar = [&](size_t at) -> float {
    return dbl ? float(load_le<double>(p + at)) : load_le<float>(p + at);
  };
  TriangleMesh mesh;
  mesh.positions.resize(vertex_count);
  for (size_t i = 0; i < vertex_count; ++i, pos += 3 * scalar)
    mesh.positions[i] = Vec3f(read_scalar(pos), read_scalar(pos + scalar), read_scalar(pos + 2 * scalar));
  if (flags & kFlagNormals) {
    mesh.normals.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i, pos += 3 * scalar)
      mesh.normals[i] = Vec3f(read_scalar(pos), read_scalar(pos + scalar), read_scalar(pos + 2 * scalar));
  }
  if (flags & kFlagTexcoords) {
    mesh.uvs.resize(vertex_count);
    for (size_t i = 0; i < vertex_count; ++i, pos += 2 * scalar) mesh.uvs[i] = Vec2f(read_scalar(pos), read_scalar(pos + scalar));
  }
  if (flags & kFlagColors) pos += vertex_count * 3 * scalar;  // vertex colours: not used by gdvr
  mesh.indices.resize(triangle_count * 3);
  for (size_t i = 0; i < triangle_count * 3; ++i, pos += index_size)
    mesh.indices[i] = index_size == 8 ? uint32_t(load_le<uint64_t>(p + pos)) : load_le<uint32_t>(p + pos);
  return mesh;
}

}  // namespace gdvr
