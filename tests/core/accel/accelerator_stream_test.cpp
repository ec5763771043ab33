// Accelerator's stream queries (intersect_stream, occluded_stream on a
// RayStreamBuffer) against its single-ray queries on the same rays: the path
// tracer's batches cast streams and trace_path single rays, and both must see
// the same scene.
#include "core/accel/accelerator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace gdvr {
namespace {

// A soup of random triangles, two static spheres and an instanced (animated)
// sphere and mesh: every geometry type and both levels of the BVH. A static
// sphere and the instanced mesh emit.
constexpr int kEmittingIds[] = {2, 4};
std::unique_ptr<Accelerator> make_scene(std::vector<int>* sphere_ids) {
  auto accel = Accelerator::create();
  EXPECT_TRUE(accel.ok());
  std::unique_ptr<Accelerator> a = std::move(accel.value());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-2.0f, 2.0f), jitter(-0.4f, 0.4f);
  std::vector<Vec3f> vertices;
  std::vector<uint32_t> indices;
  for (int t = 0; t < 300; ++t) {
    const Vec3f c(pos(rng), pos(rng), pos(rng));
    for (int k = 0; k < 3; ++k) {
      indices.push_back(uint32_t(vertices.size()));
      vertices.push_back(c + Vec3f(jitter(rng), jitter(rng), jitter(rng)));
    }
  }
  // Sphere 2 (static) and mesh 4 (instanced) emit: GeometrySet::kEmitters.
  EXPECT_TRUE(a->add_mesh(0, vertices.data(), vertices.size(), indices.data(), indices.size() / 3, false, Transform(),
                          false)
                  .ok());
  EXPECT_TRUE(a->add_sphere(1, Vec3f(0.5f, 0.2f, -0.3f), 0.7f, false, Transform(), false).ok());
  EXPECT_TRUE(a->add_sphere(2, Vec3f(-1.2f, 1.0f, 0.9f), 0.25f, false, Transform(), true).ok());
  EXPECT_TRUE(
      a->add_sphere(3, Vec3f(0, 0, 0), 0.4f, true, Transform::translate(Vec3f(1.1f, -1.3f, 0.6f)), false).ok());
  EXPECT_TRUE(a->add_mesh(4, vertices.data(), 30, indices.data(), 10, true, Transform::translate(Vec3f(0.3f, 0, 0)),
                          true)
                  .ok());
  EXPECT_TRUE(a->commit().ok());
  *sphere_ids = {1, 2, 3};
  return a;
}

struct TestRay {
  Vec3f origin, dir;
  float tmin = 0, tmax = 0;
};

std::vector<TestRay> random_rays(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-3.0f, 3.0f), aim(-2.0f, 2.0f), len(0.5f, 6.0f);
  std::vector<TestRay> rays(static_cast<size_t>(n));
  for (TestRay& r : rays) {
    r.origin = Vec3f(pos(rng), pos(rng), pos(rng));
    // Towards a point of the scene's box: most rays meet something.
    r.dir = normalize(Vec3f(aim(rng), aim(rng), aim(rng)) - r.origin);
    r.tmin = 1e-4f;
    r.tmax = (rng() % 3 == 0) ? std::numeric_limits<float>::infinity() : len(rng);
  }
  return rays;
}

// Writes rays[base..) into `buffer`, as many as it takes; returns how many.
int fill_stream(const std::vector<TestRay>& rays, size_t base, RayStreamBuffer* buffer) {
  const int m = int(std::min(rays.size() - base, size_t(RayStreamBuffer::kCapacity)));
  for (int i = 0; i < m; ++i) {
    const TestRay& r = rays[base + size_t(i)];
    buffer->set(i, r.origin, r.dir, r.tmin, r.tmax);
  }
  return m;
}

// rays[0..n) as stream queries of up to RayStreamBuffer::kCapacity rays, one
// buffer reused for all of them (as a path batch reuses its own).
void intersect_in_streams(const Accelerator& accel, const std::vector<TestRay>& rays, std::vector<RayHit>* hits,
                          std::vector<char>* found, GeometrySet set = GeometrySet::kAll,
                          RayCoherence coherence = RayCoherence::kIncoherent) {
  RayStreamBuffer buffer;
  hits->assign(rays.size(), RayHit{});
  found->assign(rays.size(), 0);
  for (size_t base = 0; base < rays.size(); base += RayStreamBuffer::kCapacity) {
    const int m = fill_stream(rays, base, &buffer);
    accel.intersect_stream(buffer, m, set, coherence);
    for (int i = 0; i < m; ++i) {
      (*found)[base + size_t(i)] = buffer.found(i);
      if (buffer.found(i)) (*hits)[base + size_t(i)] = buffer.hit(i);
    }
  }
}

std::vector<char> occluded_in_streams(const Accelerator& accel, const std::vector<TestRay>& rays) {
  RayStreamBuffer buffer;
  std::vector<char> occluded(rays.size(), 0);
  for (size_t base = 0; base < rays.size(); base += RayStreamBuffer::kCapacity) {
    const int m = fill_stream(rays, base, &buffer);
    accel.occluded_stream(buffer, m);
    for (int i = 0; i < m; ++i) occluded[base + size_t(i)] = buffer.occluded(i);
  }
  return occluded;
}

bool is_sphere(const std::vector<int>& sphere_ids, int id) {
  return std::find(sphere_ids.begin(), sphere_ids.end(), id) != sphere_ids.end();
}

TEST(AcceleratorStreamTest, ClosestHitsMatchSingleRayQueries) {
  std::vector<int> spheres;
  auto accel = make_scene(&spheres);
  int hits = 0, misses = 0, sphere_hits = 0;
  // 1 (the single-query shortcut), small, one full stream, and more than one.
  for (int n : {1, 2, 17, 64, 150, 1000}) {
    const std::vector<TestRay> rays = random_rays(n, uint32_t(n));
    std::vector<RayHit> stream_hits;
    std::vector<char> found;
    intersect_in_streams(*accel, rays, &stream_hits, &found);
    for (int i = 0; i < n; ++i) {
      const TestRay& r = rays[size_t(i)];
      RayHit single;
      const bool single_found = accel->intersect(r.origin, r.dir, r.tmin, r.tmax, &single);
      ASSERT_EQ(bool(found[size_t(i)]), single_found) << "n " << n << " ray " << i;
      if (!single_found) {
        ++misses;
        continue;
      }
      ++hits;
      const RayHit& h = stream_hits[size_t(i)];
      ASSERT_EQ(h.id, single.id) << "n " << n << " ray " << i;
      ASSERT_EQ(h.prim, single.prim);
      if (is_sphere(spheres, h.id)) {
        // Embree's packet kernel rounds a sphere's t differently.
        ++sphere_hits;
        EXPECT_NEAR(h.t, single.t, 4e-6f * single.t) << "n " << n << " ray " << i;
      } else {
        EXPECT_EQ(h.t, single.t) << "n " << n << " ray " << i;
        EXPECT_EQ(h.u, single.u);
        EXPECT_EQ(h.v, single.v);
      }
    }
  }
  // The rays must exercise every outcome.
  EXPECT_GT(hits, 400);
  EXPECT_GT(misses, 300);
  EXPECT_GT(sphere_hits, 60);
}

TEST(AcceleratorStreamTest, OcclusionMatchesSingleRayQueries) {
  std::vector<int> spheres;
  auto accel = make_scene(&spheres);
  int blocked = 0, clear = 0;
  for (int n : {1, 3, 64, 65, 1000}) {
    const std::vector<TestRay> rays = random_rays(n, 1000u + uint32_t(n));
    const std::vector<char> occluded = occluded_in_streams(*accel, rays);
    for (int i = 0; i < n; ++i) {
      const TestRay& r = rays[size_t(i)];
      ASSERT_EQ(bool(occluded[size_t(i)]), accel->occluded(r.origin, r.dir, r.tmin, r.tmax)) << "n " << n << " ray " << i;
      (occluded[size_t(i)] ? blocked : clear)++;
    }
  }
  EXPECT_GT(blocked, 100);
  EXPECT_GT(clear, 100);
}

// One RayStreamBuffer serves query after query, as a path batch's does: the
// answers of each query (closest hits, then occlusion, then closest hits
// again, of different rays and counts) are those of single-ray queries, so
// nothing a query wrote into the records leaks into the next one.
TEST(AcceleratorStreamTest, ReusedBufferAnswersEachQueryAfresh) {
  std::vector<int> spheres;
  auto accel = make_scene(&spheres);
  RayStreamBuffer buffer;
  int hits = 0, blocked = 0;
  for (int round = 0; round < 6; ++round) {
    const int n = round % 2 == 0 ? 64 : 23 + round;
    const std::vector<TestRay> rays = random_rays(n, 77u + uint32_t(round));
    ASSERT_EQ(fill_stream(rays, 0, &buffer), n);
    const bool shadow = round % 3 == 1;
    if (shadow) accel->occluded_stream(buffer, n);
    else accel->intersect_stream(buffer, n);
    for (int i = 0; i < n; ++i) {
      const TestRay& r = rays[size_t(i)];
      if (shadow) {
        ASSERT_EQ(buffer.occluded(i), accel->occluded(r.origin, r.dir, r.tmin, r.tmax)) << round << " " << i;
        blocked += buffer.occluded(i);
        continue;
      }
      RayHit single;
      ASSERT_EQ(buffer.found(i), accel->intersect(r.origin, r.dir, r.tmin, r.tmax, &single)) << round << " " << i;
      if (!buffer.found(i)) continue;
      ++hits;
      EXPECT_EQ(buffer.hit(i).id, single.id) << round << " " << i;
      EXPECT_EQ(buffer.hit(i).prim, single.prim) << round << " " << i;
    }
  }
  EXPECT_GT(hits, 50);
  EXPECT_GT(blocked, 10);
}

bool emits(int id) { return std::find(std::begin(kEmittingIds), std::end(kEmittingIds), id) != std::end(kEmittingIds); }

// The emitters-only set answers with the closest emitting geometry along the
// ray: the full scene's hit where that is an emitter, otherwise an emitter
// behind it or nothing; single and stream queries agree; and an instance
// moved after the build moves in both sets.
TEST(AcceleratorStreamTest, EmittersOnlySetFindsTheClosestEmitter) {
  std::vector<int> spheres;
  auto accel = make_scene(&spheres);
  int emitter_first = 0, emitter_behind = 0, none = 0;
  for (int moved = 0; moved < 2; ++moved) {
    if (moved) {
      ASSERT_TRUE(accel->set_instance_transform(4, Transform::translate(Vec3f(-0.7f, 0.4f, 0.2f))).ok());
      ASSERT_TRUE(accel->commit().ok());
    }
    const std::vector<TestRay> rays = random_rays(4000, 500u + uint32_t(moved));
    std::vector<RayHit> stream_hits;
    std::vector<char> found;
    intersect_in_streams(*accel, rays, &stream_hits, &found, GeometrySet::kEmitters);
    for (size_t i = 0; i < rays.size(); ++i) {
      const TestRay& r = rays[i];
      RayHit all, single;
      const bool any = accel->intersect(r.origin, r.dir, r.tmin, r.tmax, &all);
      const bool emitter = accel->intersect(r.origin, r.dir, r.tmin, r.tmax, &single, GeometrySet::kEmitters);
      ASSERT_EQ(bool(found[i]), emitter) << moved << " " << i;
      if (!emitter) {
        ASSERT_FALSE(any && emits(all.id)) << moved << " " << i;
        ++none;
        continue;
      }
      const RayHit& h = stream_hits[i];
      ASSERT_TRUE(emits(single.id)) << single.id;
      ASSERT_EQ(h.id, single.id);
      ASSERT_EQ(h.prim, single.prim);
      ASSERT_TRUE(any);
      if (emits(all.id)) {
        ASSERT_EQ(single.id, all.id) << moved << " " << i;
        ASSERT_EQ(single.prim, all.prim);
        ASSERT_EQ(single.t, all.t);
        ++emitter_first;
      } else {
        ASSERT_GT(single.t, all.t) << moved << " " << i;
        ++emitter_behind;
      }
    }
  }
  EXPECT_GT(emitter_first, 50);
  EXPECT_GT(emitter_behind, 30);
  EXPECT_GT(none, 1000);
}

// The set without emitters (camera rays of a scene that hides its emitters)
// answers with the closest non-emitting geometry: the full scene's hit where
// that emits nothing, else whatever lies behind the emitters; static and
// instanced emitters alike, single and stream queries agree, and a stream
// query leaves the buffer's masks as they were for the next query.
TEST(AcceleratorStreamTest, NonEmittersSetLooksThroughEmitters) {
  std::vector<int> spheres;
  auto accel = make_scene(&spheres);
  int plain_first = 0, behind_emitter = 0;
  const std::vector<TestRay> rays = random_rays(8000, 900u);
  // One buffer, refilled for a query of the full scene after each masked one.
  std::vector<RayHit> stream_hits(rays.size()), all_hits(rays.size());
  std::vector<char> found(rays.size()), all_found(rays.size());
  RayStreamBuffer buffer;
  for (size_t base = 0; base < rays.size(); base += RayStreamBuffer::kCapacity) {
    for (GeometrySet set : {GeometrySet::kNonEmitters, GeometrySet::kAll}) {
      const int m = fill_stream(rays, base, &buffer);
      accel->intersect_stream(buffer, m, set);
      for (int k = 0; k < m; ++k) {
        (set == GeometrySet::kAll ? all_found : found)[base + size_t(k)] = buffer.found(k);
        if (buffer.found(k)) (set == GeometrySet::kAll ? all_hits : stream_hits)[base + size_t(k)] = buffer.hit(k);
      }
    }
  }
  for (size_t i = 0; i < rays.size(); ++i) {
    const TestRay& r = rays[i];
    RayHit all, single;
    const bool any = accel->intersect(r.origin, r.dir, r.tmin, r.tmax, &all);
    const bool plain = accel->intersect(r.origin, r.dir, r.tmin, r.tmax, &single, GeometrySet::kNonEmitters);
    ASSERT_EQ(bool(found[i]), plain) << i;
    ASSERT_EQ(bool(all_found[i]), any) << i;  // the masked query left the buffer unmasked
    if (any) ASSERT_EQ(all_hits[i].id, all.id) << i;
    if (!plain) {
      ASSERT_TRUE(!any || emits(all.id)) << i;
      continue;
    }
    ASSERT_FALSE(emits(single.id)) << single.id;
    ASSERT_EQ(stream_hits[i].id, single.id) << i;
    ASSERT_TRUE(any);
    if (!emits(all.id)) {
      ASSERT_EQ(single.id, all.id) << i;
      ASSERT_EQ(single.t, all.t) << i;
      ++plain_first;
    } else {
      ASSERT_GT(single.t, all.t) << i;
      ++behind_emitter;
    }
  }
  EXPECT_GT(plain_first, 2000);
  EXPECT_GT(behind_emitter, 20);
}

// Coherent streams (RayCoherence::kCoherent: a path batch's camera rays)
// answer as single queries do, for the camera-like bundles they are meant for
// and, only slower, for rays that part: Embree's coherent packets take another
// traversal order, which may decide nothing but exact ties (the next test).
TEST(AcceleratorStreamTest, CoherentStreamsMatchSingleRayQueries) {
  std::vector<int> spheres;
  auto accel = make_scene(&spheres);
  // Bundles as a batch's camera rays: 64 rays from one eye through a small
  // patch of directions, the patch swept over the scene, plus random rays.
  std::vector<TestRay> rays;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  const Vec3f eye(0.2f, -0.1f, -6.0f);
  for (int patch = 0; patch < 40; ++patch) {
    const float cx = -0.45f + 0.9f * u01(rng), cy = -0.45f + 0.9f * u01(rng);
    for (int k = 0; k < RayStreamBuffer::kCapacity; ++k) {
      TestRay r;
      r.origin = eye;
      r.dir = normalize(Vec3f(cx + 0.01f * u01(rng), cy + 0.01f * u01(rng), 1.0f));
      r.tmin = 0;
      r.tmax = std::numeric_limits<float>::infinity();
      rays.push_back(r);
    }
  }
  const std::vector<TestRay> random = random_rays(640, 5u);
  rays.insert(rays.end(), random.begin(), random.end());
  int hits = 0, misses = 0, sphere_hits = 0, emitter_hits = 0;
  for (GeometrySet set : {GeometrySet::kAll, GeometrySet::kEmitters}) {
    std::vector<RayHit> stream_hits;
    std::vector<char> found;
    intersect_in_streams(*accel, rays, &stream_hits, &found, set, RayCoherence::kCoherent);
    for (size_t i = 0; i < rays.size(); ++i) {
      const TestRay& r = rays[i];
      RayHit single;
      const bool single_found = accel->intersect(r.origin, r.dir, r.tmin, r.tmax, &single, set);
      ASSERT_EQ(bool(found[i]), single_found) << "ray " << i;
      if (!single_found) {
        ++misses;
        continue;
      }
      (set == GeometrySet::kAll ? hits : emitter_hits)++;
      const RayHit& h = stream_hits[i];
      ASSERT_EQ(h.id, single.id) << "ray " << i;
      ASSERT_EQ(h.prim, single.prim) << "ray " << i;
      if (is_sphere(spheres, h.id)) {
        ++sphere_hits;
        EXPECT_NEAR(h.t, single.t, 4e-6f * single.t) << "ray " << i;
      } else {
        EXPECT_EQ(h.t, single.t) << "ray " << i;
        EXPECT_EQ(h.u, single.u) << "ray " << i;
        EXPECT_EQ(h.v, single.v) << "ray " << i;
      }
    }
  }
  EXPECT_GT(hits, 1000);
  EXPECT_GT(misses, 300);
  EXPECT_GT(sphere_hits, 100);
  EXPECT_GT(emitter_hits, 50);
}

// Where two triangles are met at exactly the same t, either is the closest
// hit. A mesh whose two triangles coincide: every query, single or stream,
// coherent or not, reports one of them at the t of a single query, which is
// all RayCoherence promises there.
TEST(AcceleratorStreamTest, ExactTiesReportEitherTriangleAtTheSameT) {
  auto created = Accelerator::create();
  ASSERT_TRUE(created.ok());
  std::unique_ptr<Accelerator> accel = std::move(created.value());
  const Vec3f vertices[] = {{-4, -4, 0}, {4, -4, 0}, {0, 4, 0}};  // covers every ray below
  const uint32_t indices[] = {0, 1, 2, 0, 1, 2};
  ASSERT_TRUE(accel->add_mesh(0, vertices, 3, indices, 2, false, Transform(), false).ok());
  ASSERT_TRUE(accel->commit().ok());
  std::vector<TestRay> rays;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> spread(-0.3f, 0.3f);
  for (int k = 0; k < 256; ++k) {
    TestRay r;
    r.origin = Vec3f(0, 0, -2);
    r.dir = normalize(Vec3f(spread(rng), spread(rng), 1.0f));
    r.tmin = 0;
    r.tmax = std::numeric_limits<float>::infinity();
    rays.push_back(r);
  }
  for (RayCoherence coherence : {RayCoherence::kIncoherent, RayCoherence::kCoherent}) {
    std::vector<RayHit> stream_hits;
    std::vector<char> found;
    intersect_in_streams(*accel, rays, &stream_hits, &found, GeometrySet::kAll, coherence);
    for (size_t i = 0; i < rays.size(); ++i) {
      RayHit single;
      ASSERT_TRUE(accel->intersect(rays[i].origin, rays[i].dir, rays[i].tmin, rays[i].tmax, &single)) << i;
      ASSERT_TRUE(found[i]) << i;
      EXPECT_EQ(stream_hits[i].t, single.t) << i;
      EXPECT_TRUE(stream_hits[i].prim == 0u || stream_hits[i].prim == 1u) << i;
      EXPECT_EQ(stream_hits[i].id, 0) << i;
    }
  }
}

}  // namespace
}  // namespace gdvr
