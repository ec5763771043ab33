// The path-space temporal shift (core/gradient/temporal_reconnection_shift.h)
// applied forwards (frame t -> t') and backwards: into an identical frame it
// changes nothing; with a moving shape and camera, shifting the offset back
// recovers the base path and the pair's two MIS weights sum to one for every
// technique (r_forward · r_backward = 1). Parametrised over scenes (diffuse,
// glossy plates forced through half-vector copy, environment and glossy).
#include <gtest/gtest.h>

#include <cmath>
#include <ostream>

#include "core/gradient/base_path.h"
#include "core/gradient/temporal_reconnection_shift.h"
#include "core/render/perspective_camera.h"
#include "tests/core/gradient/gpt_test_util.h"

namespace gdvr {
namespace {

struct TemporalShiftCase {
  const char* scene;
  float diffuse_roughness;  // high values force half-vector copies on glossy surfaces
  int moving_shape;         // index of the shape that moves between the frames
};
void PrintTo(const TemporalShiftCase& c, std::ostream* os) { *os << c.scene << "/thr=" << c.diffuse_roughness; }

constexpr int kW = 32, kH = 24;

// Frame t (the bundled scene) and frame t' (one shape moved, the camera moved
// a little), each with its own accelerator.
struct TwoFrames {
  Scene at_t, at_other;
  std::unique_ptr<FrameScene> scene_t, scene_other;
  PathTracerSettings path;
};

std::unique_ptr<TwoFrames> two_frames(const TemporalShiftCase& c, bool identical) {
  auto ts = test::load_test_scene(c.scene, kW, kH);
  if (!ts) return nullptr;
  auto f = std::make_unique<TwoFrames>();
  f->path = ts->render.path;
  f->at_t = ts->desc;
  f->at_other = ts->desc;
  std::vector<bool> animated(f->at_t.shapes.size(), false);
  animated[size_t(c.moving_shape)] = true;
  if (!identical) {
    // A shift of ~2 % of the scene's size and a small camera translation.
    Vec3f lo(1e30f), hi(-1e30f);
    for (const Shape& s : f->at_t.shapes)
      if (s.mesh)
        for (Vec3f p : s.mesh->positions) {
          Vec3f w = s.to_world.point(p);
          lo = Vec3f(std::min(lo.x, w.x), std::min(lo.y, w.y), std::min(lo.z, w.z));
          hi = Vec3f(std::max(hi.x, w.x), std::max(hi.y, w.y), std::max(hi.z, w.z));
        }
    const float size = max_component(hi - lo);
    Shape& moving = f->at_other.shapes[size_t(c.moving_shape)];
    moving.to_world = Transform::translate(Vec3f(0.02f * size, 0, 0.01f * size)) * moving.to_world;
    f->at_other.camera.to_world =
        Transform::translate(Vec3f(0.003f * size, 0.002f * size, 0)) * f->at_other.camera.to_world;
  }
  auto a = FrameScene::create(f->at_t, animated);
  auto b = FrameScene::create(f->at_other, animated);
  EXPECT_TRUE(a.ok() && b.ok());
  if (!a.ok() || !b.ok()) return nullptr;
  f->scene_t = std::move(a.value());
  f->scene_other = std::move(b.value());
  return f;
}

// Calls fn(base, film) for `spp` base paths of frame t per pixel (those that
// hit something and are finite).
template <typename Fn>
void for_each_base_path(const TwoFrames& f, const PerspectiveCamera& camera, uint64_t seed, uint32_t spp, Fn fn) {
  PathCounters counters;
  PathRecord base;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      for (uint32_t s = 0; s < spp; ++s) {
        Sampler sampler(seed, 0, uint32_t(x), uint32_t(y), s);
        const Vec2f j = sampler.next_2d();
        const Vec2f film(float(x) + j.x, float(y) + j.y);
        trace_base_path(*f.scene_t, f.path, camera.generate_ray(film), sampler, counters, &base);
        if (!base.invalid && !base.v.empty()) fn(base, film);
      }
}

class TemporalShiftTest : public ::testing::TestWithParam<TemporalShiftCase> {};

TEST_P(TemporalShiftTest, IntoAnIdenticalFrameTheOffsetIsTheBase) {
  auto f = two_frames(GetParam(), /* identical = */ true);
  ASSERT_TRUE(f);
  GptSettings gpt;
  gpt.diffuse_roughness = GetParam().diffuse_roughness;
  PerspectiveCamera camera(f->at_t.camera, kW, kH);
  ShapeMotion none(f->at_t, f->at_t);
  const TemporalShiftTarget target{f->scene_t.get(), &camera, &none};
  PathCounters counters;
  ShiftTrace trace;
  int paths = 0, failures = 0, off_by_2e3 = 0;
  double worst = 0, worst_ratio = 0;
  for_each_base_path(*f, camera, 11, 2, [&](const PathRecord& base, Vec2f film) {
    ++paths;
    ShiftResult r = temporal_reconnection_shift(*f->scene_t, gpt, base, film, target, counters, &trace);
    failures += r.failed ? 1 : 0;
    if (r.failed) return;
    double e = 0;
    for (int c = 0; c < 3; ++c)
      e = std::max(e, double(std::abs(r.gradient[c])) / (1e-3 + std::abs(base.indirect[c])));
    worst = std::max(worst, e);
    off_by_2e3 += e > 2e-3 ? 1 : 0;
    for (double ratio : trace.ratios)
      if (ratio > 0) worst_ratio = std::max(worst_ratio, std::abs(ratio - 1.0));
  });
  std::printf("[ temporal identity ] %s: %d paths, %d failed, worst |gradient|/|f| %.2e (%d above 2e-3), worst |r-1| "
              "%.2e\n",
              GetParam().scene, paths, failures, worst, off_by_2e3, worst_ratio);
  EXPECT_GT(paths, 200);
  // Exact where the offset stays on the base's vertices (rigid steps); after a
  // half-vector copy the traced vertex differs from the base's by float
  // noise, which a later grazing reconnection amplifies (matpreview: 1 of
  // 1536 paths at 0.7 %, since smooth plastic reconnects at its diffuse base
  // after a copied specular bounce). A wrong factor shows in most paths.
  EXPECT_LE(failures, paths / 100);
  EXPECT_LE(off_by_2e3, paths / 200);
  EXPECT_LT(worst, 1e-2);
  EXPECT_LT(worst_ratio, 0.05);
}

TEST_P(TemporalShiftTest, ShiftingBackRecoversTheBasePathAndWeightsSumToOne) {
  auto f = two_frames(GetParam(), /* identical = */ false);
  ASSERT_TRUE(f);
  GptSettings gpt;
  gpt.diffuse_roughness = GetParam().diffuse_roughness;
  PerspectiveCamera camera_t(f->at_t.camera, kW, kH), camera_other(f->at_other.camera, kW, kH);
  ShapeMotion forward_motion(f->at_t, f->at_other), backward_motion(f->at_other, f->at_t);
  const TemporalShiftTarget forward{f->scene_other.get(), &camera_other, &forward_motion};
  const TemporalShiftTarget backward{f->scene_t.get(), &camera_t, &backward_motion};
  PathCounters counters;
  ShiftTrace fwd, bwd;
  int checked = 0, failed = 0, back_failed = 0, techniques = 0, moved = 0, off_by_1e3 = 0;
  double worst_weight_sum = 0, worst_position = 0;
  for_each_base_path(*f, camera_t, 5, 4, [&](const PathRecord& base, Vec2f film) {
    ShiftResult r = temporal_reconnection_shift(*f->scene_t, gpt, base, film, forward, counters, &fwd);
    if (r.failed) {
      ++failed;
      return;
    }
    ++checked;
    for (const PathVertex& v : fwd.offset.v) moved += v.si.shape == GetParam().moving_shape ? 1 : 0;
    ShiftResult back = temporal_reconnection_shift(*f->scene_other, gpt, fwd.offset, film, backward, counters, &bwd);
    if (back.failed) {
      ++back_failed;  // must not happen (float geometry at grazing angles aside): bounded below
      return;
    }
    ASSERT_EQ(fwd.ratios.size(), bwd.ratios.size());
    for (size_t t = 0; t < fwd.ratios.size(); ++t) {
      if (fwd.ratios[t] == 0.0) continue;  // the offset lacks this technique: w = 1 on both sides
      const double w_sum = pair_mis_weight(fwd.ratios[t], 0) + pair_mis_weight(bwd.ratios[t], 0);
      worst_weight_sum = std::max(worst_weight_sum, std::abs(w_sum - 1.0));
      off_by_1e3 += std::abs(w_sum - 1.0) > 1e-3 ? 1 : 0;
      ++techniques;
    }
    ASSERT_EQ(bwd.offset.v.size(), base.v.size());
    for (size_t k = 0; k < base.v.size(); ++k) {
      const Vec3f d = bwd.offset.v[k].si.p - base.v[k].si.p;
      const Vec3f a = base.v[k].si.p;
      const float scale = 1.0f + max_component(Vec3f(std::abs(a.x), std::abs(a.y), std::abs(a.z)));
      worst_position = std::max(worst_position, double(length(d) / scale));
    }
  });
  std::printf(
      "[ temporal invertibility ] %s thr %.3g: %d pairs checked (%d vertices on the moving shape), %d forward "
      "failures, %d backward failures, %d techniques (%d with |w+w'-1| > 1e-3), worst |w+w'-1| %.2e, worst relative "
      "position error %.2e\n",
      GetParam().scene, GetParam().diffuse_roughness, checked, moved, failed, back_failed, techniques, off_by_1e3,
      worst_weight_sum, worst_position);
  EXPECT_GT(checked, 200);
  EXPECT_GT(moved, 0) << "the test needs paths through the moving shape";
  // With visibility rays aimed between the offset end points (spawn_ray_to)
  // none fails on these scenes; rays offset parallel to the segment failed
  // 0.5 % of them on veach-mis (blocked by the target's own triangle).
  EXPECT_LE(back_failed, checked / 1000);
  // Float geometry at grazing reconnections limits the agreement of a few
  // pairs; a wrong Jacobian or pdf is an O(1) error in most of them.
  EXPECT_LT(worst_weight_sum, 1e-2);
  EXPECT_LE(off_by_1e3, techniques / 200);
  EXPECT_LT(worst_position, 1e-4);
}

// Shape indices: cbox's small box (diffuse), a veach-mis plate, a matpreview
// object (glossy, under an environment).
INSTANTIATE_TEST_SUITE_P(
    Scenes, TemporalShiftTest,
    ::testing::Values(TemporalShiftCase{"cbox", 0.001f, 7}, TemporalShiftCase{"veach-mis", 0.001f, 1},
                      TemporalShiftCase{"veach-mis", 10.0f, 1}, TemporalShiftCase{"matpreview", 0.001f, 2}),
    [](const auto& info) {
      return std::string(info.param.scene == std::string("veach-mis") ? "veach_mis" : info.param.scene) +
             (info.param.diffuse_roughness > 1 ? "_all_glossy" : "");
    });

}  // namespace
}  // namespace gdvr
