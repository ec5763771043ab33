// Inputs found by the fuzz targets (tests/fuzz/, docs/correctness.md#fuzzing) that
// crashed a scene reader; each must now be a clean error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/scene/gltf_loader.h"
#include "core/scene/ply_reader.h"
#include "core/scene/serialized_reader.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

// fuzz_serialized: an offset-table entry near 2^64 wrapped `offset + 4` past
// the bounds check and read before the buffer (UBSan: pointer overflow).
TEST(SceneFuzzRegressionTest, SerializedOffsetNear2To64IsAnError) {
  std::string data = {'\x1c', '\x04', '\x04', '\x00'};  // magic 0x041C, version 4
  data += std::string(8, '\xff');                       // offset 2^64 - 1
  data += std::string("\x01\x00\x00\x00", 4);           // one mesh
  auto mesh = parse_serialized(data, 0, "wrap.serialized");
  ASSERT_FALSE(mesh.ok());
  EXPECT_EQ(mesh.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(mesh.status().message().find("offset"), std::string::npos) << mesh.status().message();
  // The same with offset 2^64 - 3 (wraps to exactly 1) and a version-3 table.
  std::string v3 = {'\x1c', '\x04', '\x03', '\x00'};
  v3 += std::string("\xfd\xff\xff\xff", 4);
  v3 += std::string("\x01\x00\x00\x00", 4);
  EXPECT_FALSE(parse_serialized(v3, 0, "v3.serialized").ok());
}

// fuzz_ply: an element without properties declaring 2^63 − 1 items (the
// count overflowed `>>` and saturated) was skipped item by item: a hang. A
// vertex count of 2^31 in a tiny file resized the arrays before reading.
TEST(SceneFuzzRegressionTest, PlyElementCountBeyondTheFileIsAnError) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement v\x9artex 4444444444444444444444444444444444444444444444vertex_"
      "indices\nend_header\n";
  auto hang = parse_ply(header + std::string(18, '\0'), "hang.ply");
  ASSERT_FALSE(hang.ok());
  EXPECT_NE(hang.status().message().find("more than the file holds"), std::string::npos) << hang.status().message();

  auto huge = parse_ply(
      "ply\nformat ascii 1.0\nelement vertex 2147483648\nproperty float x\nproperty float y\nproperty float z\n"
      "end_header\n0 0 0\n",
      "huge.ply");
  ASSERT_FALSE(huge.ok());
  EXPECT_NE(huge.status().message().find("more than the file holds"), std::string::npos) << huge.status().message();
}

// fuzz_ply: a list whose length is a float (legal PLY) of 7.7e31, or NaN,
// converted to long: undefined behaviour (UBSan) in the skipped-element, face
// and vertex loops.
TEST(SceneFuzzRegressionTest, PlyFloatListLengthOutOfRangeIsAnError) {
  auto ply_with_list = [](const std::string& element, const std::string& list_name, float length) {
    std::string h = "ply\nformat binary_little_endian 1.0\n";
    if (element != "vertex")
      h += "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
    h += "element " + element + " 1\n";
    if (element == "vertex") h += "property float x\nproperty float y\nproperty float z\n";
    h += "property list float int " + list_name + "\nend_header\n";
    std::string body(12, '\0');  // x, y, z of the one vertex; then the list's length
    body += std::string(reinterpret_cast<const char*>(&length), 4) + std::string(64, '\0');
    return h + body;
  };
  for (float length : {7.68184e31f, -1.0f, std::nanf("")}) {
    SCOPED_TRACE(length);
    EXPECT_FALSE(parse_ply(ply_with_list("edge", "vertex_pair", length), "skip.ply").ok());
    EXPECT_FALSE(parse_ply(ply_with_list("face", "vertex_indices", length), "face.ply").ok());
    EXPECT_FALSE(parse_ply(ply_with_list("vertex", "extra", length), "vertex.ply").ok());
  }
}

// fuzz_ply: a face list of float64 vertex indices holding NaN passed the
// "negative or huge" test (every comparison with NaN is false) and was
// converted to uint32_t: undefined behaviour (UBSan, corpus file ply-crash-1144...).
TEST(SceneFuzzRegressionTest, PlyNanOrOutOfRangeVertexIndexIsAnError) {
  auto ply_with_index = [](double index) {
    std::string h =
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar float64 vertex_indices\nend_header\n";
    std::string body(36, '\0');  // three vertices at the origin
    body += '\x03';
    const double indices[3] = {0.0, 1.0, index};
    body += std::string(reinterpret_cast<const char*>(indices), sizeof(indices));
    return h + body;
  };
  EXPECT_TRUE(parse_ply(ply_with_index(2.0), "ok.ply").ok());
  for (double index : {std::nan(""), -1.0, 4294967296.0, 1e300}) {
    SCOPED_TRACE(index);
    auto r = parse_ply(ply_with_index(index), "bad.ply");
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.status().to_string().find("vertex index"), std::string::npos) << r.status().to_string();
  }
}

// fuzz_gltf: a buffer URI too long to be a file name made
// std::filesystem::weakly_canonical throw (ENAMETOOLONG) through tinygltf's
// file-exists callback: std::terminate.
TEST(SceneFuzzRegressionTest, GltfBufferUriTooLongForAPathIsAnError) {
  const fs::path dir = fs::temp_directory_path() / ("gdvr_gltf_fuzz_regression_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "long_uri.gltf";
  {
    std::ofstream out(file);
    out << R"({"asset":{"version":"2.0"},"buffers":[{"byteLength":4,"uri":")" << std::string(5000, 'a')
        << R"(.bin"}],"scenes":[{"nodes":[]}],"scene":0})";
  }
  LoadOptions options;
  options.asset_root = dir.string();
  Expected<LoadedScene> loaded = Status(StatusCode::kInternal, "not run");
  ASSERT_NO_THROW(loaded = load_gltf_scene(file.string(), options));
  EXPECT_FALSE(loaded.ok());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace gdvr
