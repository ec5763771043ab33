#include <gtest/gtest.h>
#include <zlib.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/scene/mesh_repair.h"
#include "core/scene/obj_reader.h"
#include "core/scene/ply_reader.h"
#include "core/scene/serialized_reader.h"
#include "core/scene/shape_tessellation.h"

namespace gdvr {
namespace {

// ---- OBJ ----

TEST(ObjReaderTest, QuadIsFanTriangulatedWithUvsAndNormals) {
  std::istringstream in(
      "# quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
      "usemtl foo\nf 1/1/1 2/2/1 3/3/1 4/4/1\n");
  auto mesh = parse_obj(in, "quad.obj", ObjOptions{/*flip_tex_coords=*/false});
  ASSERT_TRUE(mesh.ok()) << mesh.status().to_string();
  EXPECT_EQ(mesh->positions.size(), 4u);
  EXPECT_EQ(mesh->triangle_count(), 2u);
  ASSERT_EQ(mesh->uvs.size(), 4u);
  ASSERT_EQ(mesh->normals.size(), 4u);
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{0, 1, 2, 0, 2, 3}));
  EXPECT_FLOAT_EQ(mesh->uvs[2].x, 1.0f);
  EXPECT_FLOAT_EQ(mesh->uvs[2].y, 1.0f);
}

TEST(ObjReaderTest, NegativeIndicesAndFlippedTexCoords) {
  std::istringstream in("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0.25\nf -3/-1 -2/-1 -1/-1\n");
  auto mesh = parse_obj(in, "neg.obj");
  ASSERT_TRUE(mesh.ok()) << mesh.status().to_string();
  EXPECT_EQ(mesh->triangle_count(), 1u);
  ASSERT_EQ(mesh->uvs.size(), 3u);
  EXPECT_FLOAT_EQ(mesh->uvs[0].y, 0.75f);  // Mitsuba's flip_tex_coords default
  EXPECT_TRUE(mesh->normals.empty());
}

TEST(ObjReaderTest, VertexNormalSlashSyntax) {
  std::istringstream in("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n");
  auto mesh = parse_obj(in, "vn.obj");
  ASSERT_TRUE(mesh.ok()) << mesh.status().to_string();
  EXPECT_TRUE(mesh->uvs.empty());
  EXPECT_EQ(mesh->normals.size(), 3u);
}

TEST(ObjReaderTest, OutOfRangeIndexNamesLine) {
  std::istringstream in("v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  auto mesh = parse_obj(in, "bad.obj");
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.status().message().find("bad.obj:3"), std::string::npos) << mesh.status().message();
}

TEST(ObjReaderTest, MalformedVertexNamesLine) {
  std::istringstream in("v 0 0 0\nv 1 zz 0\n");
  auto mesh = parse_obj(in, "bad.obj");
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.status().message().find("bad.obj:2"), std::string::npos);
}

TEST(ObjReaderTest, MissingFileIsNotFound) {
  auto mesh = read_obj("/nonexistent/dir/x.obj");
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.status().code(), StatusCode::kNotFound);
}

// ---- Mesh repair ----

TEST(ObjReaderTest, RepairDropsDegenerateTrianglesAndFixesNanNormals) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}};
  m.normals = {{0, 0, 1}, {NAN, 0, 0}, {0, 0, 1}, {0, 0, 1}};
  m.uvs = {{0, 0}, {NAN, 1}, {0, 1}, {1, 1}};
  m.indices = {0, 1, 2, 0, 1, 3, 0, 0, 2};  // second: collinear, third: repeated vertex
  MeshRepairReport report;
  ASSERT_TRUE(validate_and_repair_mesh(&m, "m", &report).ok());
  EXPECT_EQ(report.degenerate_triangles_dropped, 2u);
  EXPECT_EQ(m.triangle_count(), 1u);
  EXPECT_EQ(report.normals_repaired, 1u);
  for (const Vec3f& n : m.normals) EXPECT_TRUE(is_finite(n));
  EXPECT_NEAR(m.normals[1].z, 1.0f, 1e-6f);
  EXPECT_EQ(report.uvs_repaired, 1u);
  EXPECT_EQ(m.uvs[1].x, 0.0f);
}

TEST(ObjReaderTest, RepairRejectsNanPositions) {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, NAN, 0}, {0, 1, 0}};
  m.indices = {0, 1, 2};
  MeshRepairReport report;
  Status st = validate_and_repair_mesh(&m, "m", &report);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
}

// ---- PLY ----

std::string ply_header(const std::string& format, int nv, int nf, bool normals, bool uvs) {
  std::ostringstream h;
  h << "ply\nformat " << format << " 1.0\ncomment test\nelement vertex " << nv << "\n"
    << "property float x\nproperty float y\nproperty float z\n";
  if (normals) h << "property float nx\nproperty float ny\nproperty float nz\n";
  if (uvs) h << "property float u\nproperty float v\n";
  h << "element face " << nf << "\nproperty list uchar int vertex_indices\nend_header\n";
  return h.str();
}

TEST(PlyReaderTest, AsciiQuad) {
  std::string data = ply_header("ascii", 4, 1, false, true) +
                     "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n4 0 1 2 3\n";
  auto mesh = parse_ply(data, "quad.ply");
  ASSERT_TRUE(mesh.ok()) << mesh.status().to_string();
  EXPECT_EQ(mesh->positions.size(), 4u);
  EXPECT_EQ(mesh->triangle_count(), 2u);
  EXPECT_EQ(mesh->uvs.size(), 4u);
  EXPECT_TRUE(mesh->normals.empty());
}

template <typename T>
void put(std::string* s, T v, bool big_endian) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big_endian) std::reverse(b, b + sizeof(T));
  s->append(b, sizeof(T));
}

std::string binary_triangle_ply(bool big_endian) {
  std::string data = ply_header(big_endian ? "binary_big_endian" : "binary_little_endian", 3, 1, true, false);
  const float verts[3][6] = {{0, 0, 0, 0, 0, 1}, {2, 0, 0, 0, 0, 1}, {0, 3, 0, 0, 0, 1}};
  for (const auto& v : verts)
    for (float f : v) put(&data, f, big_endian);
  put<uint8_t>(&data, 3, big_endian);
  for (int32_t i : {0, 1, 2}) put(&data, i, big_endian);
  return data;
}

TEST(PlyReaderTest, BinaryLittleEndian) {
  auto mesh = parse_ply(binary_triangle_ply(false), "le.ply");
  ASSERT_TRUE(mesh.ok()) << mesh.status().to_string();
  EXPECT_EQ(mesh->triangle_count(), 1u);
  EXPECT_FLOAT_EQ(mesh->positions[2].y, 3.0f);
  ASSERT_EQ(mesh->normals.size(), 3u);
  EXPECT_FLOAT_EQ(mesh->normals[1].z, 1.0f);
}

TEST(PlyReaderTest, BinaryBigEndian) {
  auto mesh = parse_ply(binary_triangle_ply(true), "be.ply");
  ASSERT_TRUE(mesh.ok()) << mesh.status().to_string();
  EXPECT_FLOAT_EQ(mesh->positions[1].x, 2.0f);
  EXPECT_EQ(mesh->indices, (std::vector<uint32_t>{0, 1, 2}));
}

TEST(PlyReaderTest, TruncatedBinaryIsAnError) {
  std::string data = binary_triangle_ply(false);
  data.resize(data.size() - 5);
  auto mesh = parse_ply(data, "short.ply");
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.status().message().find("short.ply"), std::string::npos);
}

TEST(PlyReaderTest, BadHeaderNamesLine) {
  auto mesh = parse_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty quux x\nend_header\n", "h.ply");
  ASSERT_FALSE(mesh.ok());
  EXPECT_NE(mesh.status().message().find("h.ply:4"), std::string::npos) << mesh.status().message();
}

// ---- Mitsuba serialized ----

// Writes a version-4 file with the given meshes (positions + uvs, float).
std::string make_serialized(const std::vector<TriangleMesh>& meshes, uint16_t version = 4) {
  std::string file;
  std::vector<uint64_t> offsets;
  for (const TriangleMesh& m : meshes) {
    offsets.push_back(file.size());
    put<uint16_t>(&file, 0x041C, false);
    put<uint16_t>(&file, version, false);
    std::string raw;
    uint32_t flags = 0x1000 | (m.uvs.empty() ? 0 : 0x2) | (m.normals.empty() ? 0 : 0x1);
    put(&raw, flags, false);
    if (version == 4) raw += std::string("mesh") + '\0';
    put<uint64_t>(&raw, m.positions.size(), false);
    put<uint64_t>(&raw, m.triangle_count(), false);
    for (const Vec3f& p : m.positions)
      for (int k = 0; k < 3; ++k) put(&raw, p[k], false);
    for (const Vec3f& n : m.normals)
      for (int k = 0; k < 3; ++k) put(&raw, n[k], false);
    for (const Vec2f& uv : m.uvs) {
      put(&raw, uv.x, false);
      put(&raw, uv.y, false);
    }
    for (uint32_t i : m.indices) put(&raw, i, false);
    uLongf len = compressBound(uLong(raw.size()));
    std::string z(len, '\0');
    compress(reinterpret_cast<Bytef*>(&z[0]), &len, reinterpret_cast<const Bytef*>(raw.data()), uLong(raw.size()));
    file.append(z.data(), len);
  }
  for (uint64_t o : offsets) {
    if (version == 4) put<uint64_t>(&file, o, false);
    else put<uint32_t>(&file, uint32_t(o), false);
  }
  put<uint32_t>(&file, uint32_t(meshes.size()), false);
  return file;
}

TEST(SerializedReaderTest, PicksMeshByShapeIndex) {
  TriangleMesh a = make_rectangle_mesh(), b = make_cube_mesh();
  b.normals.clear();
  std::string data = make_serialized({a, b});
  auto m0 = parse_serialized(data, 0, "t.serialized");
  ASSERT_TRUE(m0.ok()) << m0.status().to_string();
  EXPECT_EQ(m0->triangle_count(), 2u);
  EXPECT_EQ(m0->normals.size(), 4u);
  EXPECT_FLOAT_EQ(m0->uvs[2].x, 1.0f);
  auto m1 = parse_serialized(data, 1, "t.serialized");
  ASSERT_TRUE(m1.ok()) << m1.status().to_string();
  EXPECT_EQ(m1->triangle_count(), 12u);
  EXPECT_TRUE(m1->normals.empty());
  EXPECT_EQ(m1->indices, b.indices);
}

TEST(SerializedReaderTest, Version3OffsetsAreUint32) {
  std::string data = make_serialized({make_rectangle_mesh(), make_rectangle_mesh()}, 3);
  auto m = parse_serialized(data, 1, "v3.serialized");
  ASSERT_TRUE(m.ok()) << m.status().to_string();
  EXPECT_EQ(m->positions.size(), 4u);
}

TEST(SerializedReaderTest, ShapeIndexOutOfRange) {
  std::string data = make_serialized({make_rectangle_mesh()});
  auto m = parse_serialized(data, 3, "t.serialized");
  ASSERT_FALSE(m.ok());
  EXPECT_NE(m.status().message().find("shape_index 3"), std::string::npos);
}

TEST(SerializedReaderTest, CorruptDataIsAnError) {
  std::string data = make_serialized({make_cube_mesh()});
  for (size_t i = 10; i < 40; ++i) data[i] = char(0x55);
  EXPECT_FALSE(parse_serialized(data, 0, "bad.serialized").ok());
  EXPECT_FALSE(parse_serialized("nope", 0, "tiny.serialized").ok());
}

TEST(SerializedReaderTest, MatpreviewFile) {
  std::string path = std::string(GDVR_SOURCE_DIR) + "/scenes/matpreview/matpreview.serialized";
  auto m = read_serialized(path, 2);
  ASSERT_TRUE(m.ok()) << m.status().to_string();
  EXPECT_EQ(m->positions.size(), 29439u);
  EXPECT_EQ(m->triangle_count(), 57152u);
  EXPECT_EQ(m->uvs.size(), m->positions.size());
}

// ---- Primitives ----

TEST(ObjReaderTest, PrimitivesHaveOutwardWinding) {
  for (const TriangleMesh& m : {make_rectangle_mesh(), make_cube_mesh(), make_disk_mesh(64)}) {
    ASSERT_EQ(m.normals.size(), m.positions.size());
    for (size_t t = 0; t < m.indices.size(); t += 3) {
      Vec3f p0 = m.positions[m.indices[t]], p1 = m.positions[m.indices[t + 1]], p2 = m.positions[m.indices[t + 2]];
      Vec3f geo = cross(p1 - p0, p2 - p0);
      EXPECT_GT(dot(geo, m.normals[m.indices[t]]), 0.0f);
    }
  }
  TriangleMesh cube = make_cube_mesh();
  EXPECT_EQ(cube.triangle_count(), 12u);
  double area = 0;
  TriangleMesh disk = make_disk_mesh(256);
  for (size_t t = 0; t < disk.indices.size(); t += 3)
    area += 0.5 * length(cross(disk.positions[disk.indices[t + 1]] - disk.positions[disk.indices[t]],
                               disk.positions[disk.indices[t + 2]] - disk.positions[disk.indices[t]]));
  EXPECT_NEAR(area, M_PI, 1e-3 * M_PI);
}

// A texture on a cube shows what it shows in Mitsuba 3 only with Mitsuba's uv
// layout: per face, uv as a function of the position (read off the mesh that
// Mitsuba 3.9.1's cube plugin builds). A generated scene with a checkered
// partition found gdvr's earlier layout 20-40 % off Mitsuba there.
TEST(ObjReaderTest, CubeUvLayoutIsMitsubas) {
  TriangleMesh cube = make_cube_mesh();
  for (size_t i = 0; i < cube.positions.size(); ++i) {
    const Vec3f p = cube.positions[i], n = cube.normals[i];
    Vec2f expected;
    if (n.y < -0.5f) expected = {(p.z + 1) / 2, (p.x + 1) / 2};
    else if (n.y > 0.5f) expected = {(1 - p.x) / 2, (1 - p.z) / 2};
    else if (n.x > 0.5f) expected = {(p.y + 1) / 2, (1 - p.z) / 2};
    else if (n.x < -0.5f) expected = {(p.y + 1) / 2, (p.z + 1) / 2};
    else if (n.z > 0.5f) expected = {(p.y + 1) / 2, (p.x + 1) / 2};
    else expected = {(1 - p.y) / 2, (p.x + 1) / 2};
    EXPECT_EQ(cube.uvs[i].x, expected.x) << i;
    EXPECT_EQ(cube.uvs[i].y, expected.y) << i;
  }
}

}  // namespace
}  // namespace gdvr
