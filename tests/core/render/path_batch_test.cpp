// Batched path tracing (core/render/path_batch.h) against trace_path(): the
// same paths, advanced stage by stage many at a time, must give the same
// radiance bit for bit, trace the same rays, and make the rendered image
// independent of how many paths are in flight.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "core/render/path_batch.h"
#include "core/render/pt_integrator.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

using test::load_test_scene;

constexpr int kW = 20, kH = 16;

bool same_bits(const Rgb& a, const Rgb& b) { return std::memcmp(&a, &b, sizeof(Rgb)) == 0; }

auto ray_key(const RecordedRay& r) {
  return std::make_tuple(r.shadow, r.set, r.ray.o.x, r.ray.o.y, r.ray.o.z, r.ray.d.x, r.ray.d.y, r.ray.d.z, r.ray.tmin,
                         r.ray.tmax);
}

class PathBatchTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PathBatchTest, EachPathMatchesTracePathBitForBit) {
  auto ts = load_test_scene(GetParam(), kW, kH);
  PerspectiveCamera camera(ts->desc.camera, kW, kH);
  PathTracerSettings settings = ts->render.path;
  // 150 paths: two full batches and a partial one.
  constexpr int kPaths = 150;
  std::vector<PathState> states(kPaths);
  std::vector<PathSample> single(kPaths), batched(kPaths);
  std::vector<RecordedRay> single_log, batched_log;
  PathCounters single_counters, batched_counters;
  single_counters.ray_log = &single_log;
  batched_counters.ray_log = &batched_log;
  for (int i = 0; i < kPaths; ++i) {
    const int x = (i * 7) % kW, y = (i * 3) % kH;
    Sampler sampler(42, 3, uint32_t(x), uint32_t(y), uint32_t(i));
    Vec2f j = sampler.next_2d();
    const Ray ray = camera.generate_ray({float(x) + j.x, float(y) + j.y});
    start_path(&states[size_t(i)], ray, sampler);
    single[size_t(i)] = trace_path(*ts->scene, settings, ray, sampler, single_counters);
  }
  trace_path_batch(*ts->scene, settings, states.data(), kPaths, batched_counters, batched.data());

  int nonzero = 0;
  for (int i = 0; i < kPaths; ++i) {
    EXPECT_TRUE(same_bits(single[size_t(i)].radiance, batched[size_t(i)].radiance)) << "path " << i;
    EXPECT_TRUE(same_bits(single[size_t(i)].direct, batched[size_t(i)].direct)) << "path " << i;
    nonzero += !single[size_t(i)].radiance.is_black();
  }
  EXPECT_GT(nonzero, kPaths / 4);  // the comparison is not of black pixels only
  EXPECT_EQ(single_counters.rays, batched_counters.rays);
  EXPECT_EQ(single_counters.invalid_samples, batched_counters.invalid_samples);
  // The same rays, cast in another order.
  ASSERT_EQ(single_log.size(), batched_log.size());
  auto by_key = [](const RecordedRay& a, const RecordedRay& b) { return ray_key(a) < ray_key(b); };
  std::sort(single_log.begin(), single_log.end(), by_key);
  std::sort(batched_log.begin(), batched_log.end(), by_key);
  for (size_t k = 0; k < single_log.size(); ++k)
    ASSERT_TRUE(ray_key(single_log[k]) == ray_key(batched_log[k])) << "ray " << k;
  EXPECT_GT(std::count_if(single_log.begin(), single_log.end(), [](const RecordedRay& r) { return r.shadow; }), 0);
}

TEST_P(PathBatchTest, RenderDoesNotDependOnPathsInFlight) {
  auto ts = load_test_scene(GetParam(), kW, kH);
  FrameRenderSettings rs = ts->render;
  rs.spp = 6;
  rs.seed = 17;
  rs.threads = 2;
  std::vector<FrameRenderResult> results;
  for (int in_flight : {1, 5, kPathBatch}) {
    rs.paths_in_flight = in_flight;
    auto r = render_frame_pt(*ts->scene, rs, 0, {});
    ASSERT_TRUE(r.ok()) << r.status().to_string();
    results.push_back(std::move(r.value()));
  }
  for (size_t k = 1; k < results.size(); ++k) {
    EXPECT_EQ(results[0].rays, results[k].rays);
    ASSERT_EQ(results[0].color.data().size(), results[k].color.data().size());
    EXPECT_EQ(0, std::memcmp(results[0].color.data().data(), results[k].color.data().data(),
                             results[0].color.data().size() * sizeof(float)));
    EXPECT_EQ(0, std::memcmp(results[0].variance.data().data(), results[k].variance.data().data(),
                             results[0].variance.data().size() * sizeof(float)));
  }
}

// Embree's packet kernel rounds a sphere's t differently from its single-ray
// kernel; the hit point must not inherit that (FrameScene::interaction solves
// it from the ray), or batched and single paths would part at sphere hits.
TEST(PathBatchSphereTest, SphereHitsAreTheSameFromStreamsAndSingleCasts) {
  auto ts = load_test_scene("veach-mis", kW, kH);
  const FrameScene& scene = *ts->scene;
  std::vector<Ray> rays;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (const Shape& shape : ts->desc.shapes) {
    if (shape.type != ShapeType::kSphere) continue;
    const Vec3f center = shape.to_world.point(Vec3f(0, 0, 0));
    const float radius = length(shape.to_world.vector(Vec3f(1, 0, 0)));
    for (int i = 0; i < 600; ++i) {
      const Vec3f origin = center + Vec3f(unit(rng), unit(rng), unit(rng)) * (8.0f * radius + 2.0f);
      const Vec3f target = center + Vec3f(unit(rng), unit(rng), unit(rng)) * (0.55f * radius);
      rays.push_back(Ray{origin, normalize(target - origin), 0.0f, kInfinity});
    }
  }
  ASSERT_GE(rays.size(), size_t(1200));
  int sphere_hits = 0;
  for (size_t base = 0; base < rays.size(); base += kPathBatch) {
    const int n = int(std::min(rays.size() - base, size_t(kPathBatch)));
    RayStream stream;
    for (int k = 0; k < n; ++k) set_stream_ray(stream, k, rays[base + size_t(k)]);
    scene.accelerator().intersect_stream(stream, n);
    for (int k = 0; k < n; ++k) {
      const Ray& r = rays[base + size_t(k)];
      SurfaceInteraction single, streamed;
      ASSERT_EQ(scene.intersect(r, &single), stream.found(k));
      if (!stream.found(k)) continue;
      scene.interaction(r, stream.hit(k), &streamed);
      ASSERT_EQ(single.shape, streamed.shape);
      if (ts->desc.shapes[size_t(single.shape)].type != ShapeType::kSphere) continue;
      ++sphere_hits;
      EXPECT_EQ(0, std::memcmp(&single.p, &streamed.p, sizeof(Vec3f))) << "ray " << base + size_t(k);
      EXPECT_EQ(0, std::memcmp(&single.n, &streamed.n, sizeof(Vec3f))) << "ray " << base + size_t(k);
      EXPECT_EQ(0, std::memcmp(&single.uv, &streamed.uv, sizeof(Vec2f))) << "ray " << base + size_t(k);
    }
  }
  EXPECT_GT(sphere_hits, int(rays.size()) / 2);
}

// A path's last ray under max_depth looks for emitters first (cast_last: an
// emitters-only closest hit, then an any-hit query up to it). What
// add_emission() then adds must be, bit for bit, what the closest hit in the
// whole scene gives, for single casts and for streams, on area emitters
// (veach-mis: spheres and a quad; cbox: a quad) and an environment map
// (matpreview, whose max_depth is set here).
class LastRayTest : public ::testing::TestWithParam<std::string> {};

TEST_P(LastRayTest, EmittersFirstAddsWhatTheClosestHitAdds) {
  auto ts = load_test_scene(GetParam(), kW, kH);
  const FrameScene& scene = *ts->scene;
  PathTracerSettings settings = ts->render.path;
  settings.max_depth = 3;
  const int last_depth = last_vertex_depth(settings);
  PerspectiveCamera camera(ts->desc.camera, kW, kH);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < 400; ++i) rays.push_back(camera.generate_ray({unit(rng) * kW, unit(rng) * kH}));
  // Rays from inside the scene (blocked or not) and rays aimed at each
  // emitting shape, so that emitter hits and blocked emitters are many.
  for (int i = 0; i < 300; ++i) {
    const Ray from_camera = camera.generate_ray({unit(rng) * kW, unit(rng) * kH});
    SurfaceInteraction si;
    if (!scene.intersect(from_camera, &si)) continue;
    const Vec3f d = normalize(Vec3f(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f));
    rays.push_back(si.spawn_ray(dot(d, si.n) >= 0 ? d : -d));
  }
  // From the camera and from surfaces the camera sees towards points of each
  // area emitter's bounds: the emitter is seen, or something is in the way.
  for (const Bounds3f& b : scene.area_emitter_bounds()) {
    for (int k = 0; k < 600; ++k) {
      const Vec3f target = b.lo + (b.hi - b.lo) * Vec3f(unit(rng), unit(rng), unit(rng));
      const Ray from_camera = camera.generate_ray({unit(rng) * kW, unit(rng) * kH});
      SurfaceInteraction si;
      if (k % 2 == 0 || !scene.intersect(from_camera, &si)) {
        const Vec3f origin = from_camera.o + from_camera.d * (0.5f * unit(rng));
        rays.push_back(Ray{origin, normalize(target - origin), 0.0f, kInfinity});
      } else {
        rays.push_back(si.spawn_ray(normalize(target - si.p)));
      }
    }
  }
  auto start = [&](const Ray& ray, PathState* st) {
    start_path(st, ray, Sampler(7, 0, 1, 2, 3));
    st->depth = last_depth;
    st->throughput = Rgb(0.5f, 0.25f, 2.0f);
    st->prev_p = ray.o;
    st->prev_bsdf_pdf = 0.7f;
    st->prev_bsdf_delta = false;
  };
  std::vector<PathState> streamed(rays.size());
  for (size_t i = 0; i < rays.size(); ++i) start(rays[i], &streamed[i]);
  PathCounters counters;
  RayStream stream;
  for (size_t base = 0; base < rays.size(); base += kPathBatch) {
    int which[kPathBatch];
    const int n = int(std::min(rays.size() - base, size_t(kPathBatch)));
    for (int k = 0; k < n; ++k) which[k] = int(base) + k;
    cast_closest_stream(scene, settings, streamed.data(), which, n, stream, counters);
  }
  // What the rays met, by the closest hit in the whole scene.
  int emitter_seen = 0, emitter_hidden = 0, environment_seen = 0, environment_hidden = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    PathState full, single;
    start(rays[i], &full);
    start(rays[i], &single);
    RayHit hit;
    full.hit = scene.intersect_hit(rays[i], &hit);
    if (full.hit) scene.interaction(rays[i], hit, &full.si);
    cast_closest(scene, settings, &single, counters);
    for (PathState* st : {&full, &single, &streamed[i]}) add_emission(scene, settings, st);
    for (const PathState* st : {&single, &streamed[i]}) {
      ASSERT_TRUE(same_bits(st->result, full.result)) << "ray " << i;
      ASSERT_TRUE(same_bits(st->direct, full.direct)) << "ray " << i;
      ASSERT_FALSE(st->continues);
    }
    RayHit emitter;
    if (scene.intersect_emitter_hit(rays[i], &emitter)) {
      // (The back of a one-sided emitter is met but emits nothing: neither.)
      if (!(full.hit && hit.id == emitter.id)) ++emitter_hidden;
      else if (!full.result.is_black()) ++emitter_seen;
    } else if (scene.has_environment()) {
      (full.hit ? environment_hidden : environment_seen) += 1;
    }
  }
  // Every outcome occurs many times.
  if (scene.area_emitter_bounds().empty()) {
    EXPECT_GT(environment_seen, 100);
    EXPECT_GT(environment_hidden, 100);
  } else {
    EXPECT_GT(emitter_seen, 100);
    EXPECT_GT(emitter_hidden, 30);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, LastRayTest, ::testing::Values("cbox", "veach-mis", "matpreview"),
                         [](const auto& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

INSTANTIATE_TEST_SUITE_P(Scenes, PathBatchTest, ::testing::Values("cbox", "veach-mis", "matpreview"),
                         [](const auto& info) {
                           std::string n = info.param;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
}  // namespace gdvr
