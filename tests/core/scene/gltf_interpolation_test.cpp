// The InterpolationTest test: every STEP / LINEAR / CUBICSPLINE
// translation, rotation and scale node of Khronos' InterpolationTest sample,
// evaluated through the loader's tracks and apply_animation, equals the key
// values at the keys and a value computed here from the raw key data with the
// glTF 2.0 spec's formulas (Appendix C) between them. Also BoxAnimated's
// hierarchy: a child inherits its parent's animated translation.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <nlohmann/json.hpp>

#include "core/scene/gltf_loader.h"

namespace gdvr {
namespace {

using Json = nlohmann::json;
using Vec = std::vector<double>;

std::string sample_path(const std::string& rel) { return std::string(GDVR_SOURCE_DIR) + "/scenes/gltf/" + rel; }

// Reads a tightly packed float accessor straight from the .bin (independent of
// the loader's accessor code).
struct RawGltf {
  Json doc;
  std::vector<char> bin;
  RawGltf(const std::string& gltf, const std::string& bin_path) {
    std::ifstream in(gltf);
    doc = Json::parse(in);
    std::ifstream b(bin_path, std::ios::binary);
    bin.assign(std::istreambuf_iterator<char>(b), {});
  }
  Vec floats(int accessor) const {
    const Json& a = doc["accessors"][size_t(accessor)];
    const Json& v = doc["bufferViews"][a["bufferView"].get<size_t>()];
    size_t offset = v.value("byteOffset", size_t(0)) + a.value("byteOffset", size_t(0));
    static const std::map<std::string, size_t> kComponents = {{"SCALAR", 1}, {"VEC3", 3}, {"VEC4", 4}};
    size_t n = a["count"].get<size_t>() * kComponents.at(a["type"].get<std::string>());
    Vec out(n);
    for (size_t i = 0; i < n; ++i) {
      float f;
      std::memcpy(&f, bin.data() + offset + 4 * i, 4);
      out[i] = f;
    }
    return out;
  }
};

// ---- The spec's formulas, written out independently of the loader ----

Vec step_or_linear(const Vec& times, const Vec& values, int nc, double t, bool step) {
  size_t n = times.size();
  auto key = [&](size_t k) { return Vec(values.begin() + long(k * nc), values.begin() + long((k + 1) * nc)); };
  if (t <= times[0]) return key(0);
  if (t >= times[n - 1]) return key(n - 1);
  size_t k = 0;
  while (times[k + 1] <= t) ++k;
  Vec a = key(k), b = key(k + 1), out = Vec(size_t(nc), 0.0);
  if (step) return a;
  double u = (t - times[k]) / (times[k + 1] - times[k]);
  if (nc == 4) {  // slerp, shorter arc
    double d = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
    double s = d < 0 ? -1 : 1;
    double theta = std::acos(std::min(1.0, std::abs(d)));
    for (int c = 0; c < 4; ++c)
      out[size_t(c)] = theta < 1e-9 ? a[size_t(c)]
                                    : (std::sin((1 - u) * theta) * a[size_t(c)] + s * std::sin(u * theta) * b[size_t(c)]) /
                                          std::sin(theta);
    return out;
  }
  for (int c = 0; c < nc; ++c) out[size_t(c)] = a[size_t(c)] + u * (b[size_t(c)] - a[size_t(c)]);
  return out;
}

Vec cubic_spline(const Vec& times, const Vec& values, int nc, double t) {
  size_t n = times.size();
  auto part = [&](size_t k, int which) {  // 0 in-tangent, 1 value, 2 out-tangent
    return Vec(values.begin() + long((3 * k + size_t(which)) * nc), values.begin() + long((3 * k + size_t(which) + 1) * nc));
  };
  Vec out = Vec(size_t(nc), 0.0);
  if (t <= times[0]) out = part(0, 1);
  else if (t >= times[n - 1]) out = part(n - 1, 1);
  else {
    size_t k = 0;
    while (times[k + 1] <= t) ++k;
    double td = times[k + 1] - times[k], s = (t - times[k]) / td;
    Vec vk = part(k, 1), bk = part(k, 2), vk1 = part(k + 1, 1), ak1 = part(k + 1, 0);
    for (int c = 0; c < nc; ++c) {
      size_t i = size_t(c);
      out[i] = (2 * s * s * s - 3 * s * s + 1) * vk[i] + td * (s * s * s - 2 * s * s + s) * bk[i] +
               (-2 * s * s * s + 3 * s * s) * vk1[i] + td * (s * s * s - s * s) * ak1[i];
    }
  }
  if (nc == 4) {
    double l = std::sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2] + out[3] * out[3]);
    for (double& x : out) x /= l;
  }
  return out;
}

// T * R * S, glTF's node matrix, written out again here.
Matrix4 trs(const Vec& t, const Vec& q, const Vec& s) {
  double x = q[0], y = q[1], z = q[2], w = q[3];
  double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                    {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                    {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  Matrix4 m = Matrix4::identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) m.m[i][j] = r[i][j] * s[size_t(j)];
    m.m[i][3] = t[size_t(i)];
  }
  return m;
}

const Shape* find_shape(const Scene& scene, const std::string& id) {
  for (const Shape& s : scene.shapes)
    if (s.id == id) return &s;
  return nullptr;
}

void expect_matrix_near(const Matrix4& a, const Matrix4& b, double tol, const std::string& what) {
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) EXPECT_NEAR(a.m[i][j], b.m[i][j], tol) << what << " [" << i << "][" << j << "]";
}

TEST(GltfInterpolationTest, EveryChannelMatchesTheSpecAtAndBetweenKeys) {
  RawGltf raw(sample_path("InterpolationTest/InterpolationTest.gltf"), sample_path("InterpolationTest/interpolation.bin"));
  auto loaded = load_gltf_scene(sample_path("InterpolationTest/InterpolationTest.gltf"), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  const Json& doc = raw.doc;
  ASSERT_EQ(doc["animations"].size(), 9u);
  int checked = 0;
  for (const Json& anim : doc["animations"]) {
    const Json& ch = anim["channels"][0];
    const Json& smp = anim["samplers"][ch["sampler"].get<size_t>()];
    const int node = ch["target"]["node"].get<int>();
    const std::string path = ch["target"]["path"].get<std::string>();
    const std::string interp = smp["interpolation"].get<std::string>();
    const Json& jn = doc["nodes"][size_t(node)];
    const std::string name = jn["name"].get<std::string>();
    Vec times = raw.floats(smp["input"].get<int>()), values = raw.floats(smp["output"].get<int>());
    const int nc = path == "rotation" ? 4 : 3;

    // The times to check: every key, the midpoint and quarter point of every
    // interval, and outside the key range.
    std::vector<double> probe = {times.front() - 0.5, times.back() + 0.5};
    for (size_t k = 0; k < times.size(); ++k) {
      probe.push_back(times[k]);
      if (k + 1 < times.size()) {
        probe.push_back(0.5 * (times[k] + times[k + 1]));
        probe.push_back(0.75 * times[k] + 0.25 * times[k + 1]);
      }
    }
    for (double t : probe) {
      Vec v = interp == "CUBICSPLINE" ? cubic_spline(times, values, nc, t)
                                      : step_or_linear(times, values, nc, t, interp == "STEP");
      Vec tr = jn.value("translation", Vec{0, 0, 0}), rot = jn.value("rotation", Vec{0, 0, 0, 1}),
          sc = jn.value("scale", Vec{1, 1, 1});
      (path == "translation" ? tr : path == "rotation" ? rot : sc) = v;
      Scene scene = loaded->scene;
      ASSERT_TRUE(apply_animation(loaded->animation, t, &scene).ok());
      const Shape* shape = find_shape(scene, name);
      ASSERT_NE(shape, nullptr) << name;
      expect_matrix_near(shape->to_world.matrix(), trs(tr, rot, sc), 2e-6,
                         interp + " " + path + " (" + name + ") at t = " + std::to_string(t));
    }
    ++checked;
  }
  EXPECT_EQ(checked, 9);
}

// Spot values worked by hand from the key data, so that a shared mistake in the
// formulas above cannot hide.
TEST(GltfInterpolationTest, HandWorkedValues) {
  auto loaded = load_gltf_scene(sample_path("InterpolationTest/InterpolationTest.gltf"), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  auto at = [&](const std::string& id, double t) {
    Scene scene = loaded->scene;
    EXPECT_TRUE(apply_animation(loaded->animation, t, &scene).ok());
    return find_shape(scene, id)->to_world;
  };
  // LINEAR translation (Cube.009): y keys 6.621 at t = 0 and 10 at t = 5/12 (x, z fixed).
  Vec3f p = at("Cube.009", 0.5 * 0.4166666567325592).point(Vec3f(0.0f));
  EXPECT_NEAR(p.y, 0.5 * (6.6210 + 10.0), 2e-4);
  // STEP translation (Cube.006): y keys 6.6652 (t = 0) and 10 (t = 0.4583): hold the earlier key.
  EXPECT_NEAR(at("Cube.006", 0.45).point(Vec3f(0.0f)).y, 6.6652, 2e-4);
  EXPECT_NEAR(at("Cube.006", 0.4583334).point(Vec3f(0.0f)).y, 10.0, 1e-5);
  // LINEAR rotation (Cube.005): keys 0 and -45 degrees about z; halfway is -22.5 degrees.
  Vec3f x = at("Cube.005", 0.5 * 0.4166666567325592).vector(Vec3f(1, 0, 0));
  EXPECT_NEAR(std::atan2(x.y, x.x) * 180.0 / 3.14159265358979, -22.5, 1e-3);
  // CUBICSPLINE scale (Cube.002): keys 1 and 0.5 with zero tangents: the
  // Hermite midpoint is the plain average 0.75 ((2u^3 - 3u^2 + 1) = 0.5 at u = 1/2).
  double mid = 0.5 * (0.0416666679084301 + 0.4166666567325592);
  EXPECT_NEAR(at("Cube.002", mid).vector(Vec3f(1, 0, 0)).x, 0.75, 1e-5);
  // ... and at u = 1/4: h00 = 2/64 - 3/16 + 1 = 0.84375, h01 = 0.15625, so
  // 0.84375 * 1 + 0.15625 * 0.5 = 0.921875.
  double quarter = 0.75 * 0.0416666679084301 + 0.25 * 0.4166666567325592;
  EXPECT_NEAR(at("Cube.002", quarter).vector(Vec3f(1, 0, 0)).x, 0.921875, 1e-5);
}

TEST(GltfInterpolationTest, TracksTargetTheAnimatedShapesOnly) {
  auto loaded = load_gltf_scene(sample_path("InterpolationTest/InterpolationTest.gltf"), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  std::set<std::string> targets;
  for (const Track& t : loaded->animation.tracks) {
    targets.insert(t.target);
    EXPECT_TRUE(t.curve != nullptr);
    EXPECT_GE(t.keys.size(), 5u);
  }
  EXPECT_EQ(targets, (std::set<std::string>{"Cube", "Cube.001", "Cube.002", "Cube.003", "Cube.004", "Cube.005",
                                            "Cube.006", "Cube.008", "Cube.009"}));
  EXPECT_TRUE(validate_animation(loaded->animation, loaded->scene).ok());
}

TEST(GltfInterpolationTest, BoxAnimatedChildInheritsParentTranslation) {
  RawGltf raw(sample_path("BoxAnimated/BoxAnimated.gltf"), sample_path("BoxAnimated/BoxAnimated0.bin"));
  auto loaded = load_gltf_scene(sample_path("BoxAnimated/BoxAnimated.gltf"), LoadOptions());
  ASSERT_TRUE(loaded.ok()) << loaded.status().to_string();
  // nodes[0] (translation animated) -> nodes[1] -> nodes[2] (mesh 0, rotation
  // animated); nodes[3] (mesh 1) is static. Unnamed nodes get "node<index>".
  std::set<std::string> targets;
  for (const Track& t : loaded->animation.tracks) targets.insert(t.target);
  EXPECT_EQ(targets, std::set<std::string>{"node2"});
  const Json& ch = raw.doc["animations"][0]["channels"][1];
  ASSERT_EQ(ch["target"]["path"], "translation");
  const Json& smp = raw.doc["animations"][0]["samplers"][ch["sampler"].get<size_t>()];
  Vec times = raw.floats(smp["input"].get<int>()), values = raw.floats(smp["output"].get<int>());
  bool moved = false;
  for (double t = 0; t <= 4.0; t += 0.25) {
    Scene scene = loaded->scene;
    ASSERT_TRUE(apply_animation(loaded->animation, t, &scene).ok());
    Vec expected = step_or_linear(times, values, 3, t, false);
    Vec3f origin = find_shape(scene, "node2")->to_world.point(Vec3f(0.0f));
    EXPECT_NEAR(origin.x, expected[0], 1e-5) << "t = " << t;
    EXPECT_NEAR(origin.y, expected[1], 1e-5) << "t = " << t;
    EXPECT_NEAR(origin.z, expected[2], 1e-5) << "t = " << t;
    moved = moved || expected[1] > 1.0;
    EXPECT_EQ(find_shape(scene, "node3")->to_world, find_shape(loaded->scene, "node3")->to_world);
  }
  EXPECT_TRUE(moved);
}

}  // namespace
}  // namespace gdvr
