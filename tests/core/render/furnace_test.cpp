// White-furnace tests: scenes whose pixel values are known in closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"

namespace gdvr {
namespace {

Bsdf diffuse(float albedo) {
  Bsdf b;
  b.type = BsdfType::kDiffuse;
  b.reflectance = Texture::constant(Rgb(albedo));
  b.finalize();
  return b;
}

Shape sphere(float radius, int bsdf, int emitter, bool flip) {
  Shape s;
  s.type = ShapeType::kSphere;
  s.to_world = Transform::scale(Vec3f(radius));
  s.bsdf = bsdf;
  s.emitter = emitter;
  s.flip_normals = flip;
  return s;
}

Camera camera_at(Vec3f origin, Vec3f target, float fov) {
  Camera c;
  EXPECT_TRUE(Transform::look_at(origin, target, {0, 1, 0}, &c.to_world));
  c.fov = fov;
  c.fov_axis = FovAxis::kX;
  return c;
}

struct MeanAndError {
  double mean = 0, std_error = 0;
};

// Mean over all pixels of channel 0, with the standard error from the per-pixel variances.
MeanAndError image_mean(const FrameRenderResult& r) {
  MeanAndError m;
  double var_sum = 0;
  size_t n = r.color.pixel_count();
  for (int y = 0; y < r.color.height(); ++y)
    for (int x = 0; x < r.color.width(); ++x) {
      m.mean += r.color.at(x, y, 0);
      var_sum += r.variance.at(x, y, 0);
    }
  m.mean /= double(n);
  m.std_error = std::sqrt(var_sum) / double(n);
  return m;
}

FrameRenderResult render(const Scene& scene, int spp, int max_depth, int threads = 0, int size = 16) {
  auto fs = FrameScene::create(scene, {});
  EXPECT_TRUE(fs.ok()) << fs.status().to_string();
  FrameRenderSettings settings;
  settings.width = settings.height = size;
  settings.spp = spp;
  settings.seed = 7;
  settings.threads = threads;
  settings.path.max_depth = max_depth;
  auto r = render_frame_pt(*fs.value(), settings, 0, {});
  EXPECT_TRUE(r.ok()) << r.status().to_string();
  return std::move(r.value());
}

// A convex diffuse object of albedo rho under a uniform environment of radiance
// 1 reflects exactly rho: light scatters once and leaves (convexity).
TEST(FurnaceTest, ConvexDiffuseSphereUnderUniformSkyReflectsItsAlbedo) {
  for (float rho : {0.3f, 0.8f}) {
    Scene scene;
    scene.bsdfs.push_back(diffuse(rho));
    scene.shapes.push_back(sphere(1.0f, 0, -1, false));
    Emitter sky;
    sky.type = EmitterType::kConstant;
    sky.radiance = Rgb(1.0f);
    scene.emitters.push_back(sky);
    // Narrow field of view: every pixel sees the sphere.
    scene.camera = camera_at({0, 0, -5}, {0, 0, 0}, 5.0f);
    FrameRenderResult r = render(scene, 64, -1);
    MeanAndError m = image_mean(r);
    EXPECT_NEAR(m.mean, rho, 5 * m.std_error + 1e-4) << "rho=" << rho;
    EXPECT_GT(m.std_error, 0.0);
  }
}

// Inside a closed emitting sphere of radiance Le and albedo rho, radiance is
// Le * (1 + rho + ... + rho^(k-1)) with k = max_depth path segments, Le / (1 - rho) unbounded.
TEST(FurnaceTest, ClosedEmittingSphereMatchesGeometricSeries) {
  const float rho = 0.5f, le = 2.0f;
  Scene scene;
  scene.bsdfs.push_back(diffuse(rho));
  Emitter area;
  area.type = EmitterType::kArea;
  area.radiance = Rgb(le);
  area.shape = 0;
  scene.emitters.push_back(area);
  scene.shapes.push_back(sphere(3.0f, 0, 0, /*flip=*/true));
  scene.camera = camera_at({0, 0, 0}, {0, 0, 1}, 60.0f);
  for (int max_depth : {1, 2, 3, 6, -1}) {
    double expected = max_depth < 0 ? le / (1.0 - rho) : le * (1.0 - std::pow(rho, max_depth)) / (1.0 - rho);
    FrameRenderResult r = render(scene, 32, max_depth);
    MeanAndError m = image_mean(r);
    EXPECT_NEAR(m.mean, expected, 5 * m.std_error + 1e-4 * expected) << "max_depth=" << max_depth;
  }
}

TEST(FurnaceTest, ImageDoesNotDependOnThreadCount) {
  Scene scene;
  scene.bsdfs.push_back(diffuse(0.7f));
  scene.shapes.push_back(sphere(1.0f, 0, -1, false));
  Emitter sky;
  sky.type = EmitterType::kConstant;
  sky.radiance = Rgb(1.0f);
  scene.emitters.push_back(sky);
  scene.camera = camera_at({0, 0, -4}, {0, 0, 0}, 40.0f);
  FrameRenderResult one = render(scene, 4, -1, 1, 24);
  FrameRenderResult two = render(scene, 4, -1, 2, 24);
  ASSERT_EQ(one.color.data().size(), two.color.data().size());
  EXPECT_EQ(one.color.data(), two.color.data());
  EXPECT_EQ(one.rays, two.rays);
}

TEST(FurnaceTest, CancelledRenderReturnsCancelled) {
  Scene scene;
  scene.bsdfs.push_back(diffuse(0.5f));
  scene.shapes.push_back(sphere(1.0f, 0, -1, false));
  scene.camera = camera_at({0, 0, -4}, {0, 0, 0}, 40.0f);
  auto fs = FrameScene::create(scene, {});
  ASSERT_TRUE(fs.ok());
  std::atomic<bool> cancel{true};
  FrameRenderSettings settings;
  settings.width = settings.height = 32;
  FrameRenderControl control;
  control.cancel = &cancel;
  auto r = render_frame_pt(*fs.value(), settings, 0, control);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kCancelled);
}

}  // namespace
}  // namespace gdvr
