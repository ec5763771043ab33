// Motion-compensated temporal constraints (docs/tgpt.md, "dt and motion"):
// the replay map of pass A (core/temporal/replay_map.h), stage 2's replayed
// pairs, and on a camera pan over a fine checkerboard the compensated dt's
// variance against the same-pixel dt's and its mean against converged PT.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/gradient/gpt_integrator.h"
#include "core/render/frame_scene.h"
#include "core/scene/mitsuba_loader.h"
#include "core/temporal/change_detection.h"
#include "core/temporal/motion_vectors.h"
#include "core/temporal/replay_map.h"
#include "core/temporal/temporal_buffers.h"
#include "core/temporal/tgpt_frame.h"
#include "seed_mean_z.h"

namespace gdvr {
namespace {

const std::vector<std::string> kRgb = {"R", "G", "B"};

// A motion field of w x h pixels, every pixel valid with offset (mx, my).
Image uniform_field(int w, int h, float mx, float my) {
  Image f(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      f.at(x, y, 0) = mx;
      f.at(x, y, 1) = my;
      f.at(x, y, 2) = 1.0f;
    }
  return f;
}

// ---------------------------------------------------------------------------
// The replay map and stage 2's pairs on synthetic fields
// ---------------------------------------------------------------------------

TEST(TemporalReplayMapTest, SourcesFollowTheBackwardFieldWithTheRemainderAsShift) {
  // Frame t+1's surface came from 1.3 px to the left and 0.6 px down: pixel q
  // replays the stream of q + (round(−1.3), round(0.6)) = q + (−1, 1).
  const int w = 6, h = 5;
  Image back = uniform_field(w, h, -1.3f, 0.6f);
  back.at(3, 2, 2) = 0.0f;  // no surface to follow: own stream
  back.at(3, 2, 0) = back.at(3, 2, 1) = 0.0f;
  ReplayMap map = build_replay_map(back);
  ASSERT_EQ(map.width, w);
  ASSERT_EQ(map.height, h);
  ASSERT_EQ(map.sources.size(), size_t(w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
      const ReplaySource& r = map.at(x, y);
      const bool own = (x == 3 && y == 2) || x == 0 || y == h - 1;  // invalid, or source outside the image
      if (own) {
        EXPECT_EQ(r.x, uint32_t(x));
        EXPECT_EQ(r.y, uint32_t(y));
        EXPECT_EQ(r.shift.x, 0.0f);
        EXPECT_EQ(r.shift.y, 0.0f);
        continue;
      }
      EXPECT_EQ(r.x, uint32_t(x - 1));
      EXPECT_EQ(r.y, uint32_t(y + 1));
      // δ = s − q − b = (−1 + 1.3, 1 − 0.6).
      EXPECT_NEAR(r.shift.x, 0.3f, 1e-6f);
      EXPECT_NEAR(r.shift.y, 0.4f, 1e-6f);
    }
}

TEST(TemporalReplayMapTest, ShiftStaysWithinHalfAPixelAndRotationStaysInThePixel) {
  // One row, a different backward offset per pixel, ties included: the source
  // is the pixel whose footprint holds the landing point, δ ∈ (−0.5, 0.5].
  const float offsets[] = {0.0f, -0.5f, 0.5f, -0.49f, 0.49f, 1.5f, -2.5f, 1.25f, -1.75f, 0.999f};
  const int w = int(sizeof(offsets) / sizeof(offsets[0]));
  Image back(w, 1, 3);
  for (int x = 0; x < w; ++x) {
    back.at(x, 0, 0) = offsets[x];
    back.at(x, 0, 2) = 1.0f;
  }
  ReplayMap map = build_replay_map(back);
  const int expected_source[] = {0, 1, 3, 3, 4, 7, 4, 8, 6, 10};  // 10: outside, own stream
  for (int x = 0; x < w; ++x) {
    SCOPED_TRACE("pixel " + std::to_string(x));
    const ReplaySource& r = map.at(x, 0);
    EXPECT_EQ(r.y, 0u);
    if (expected_source[x] >= w) {
      EXPECT_EQ(int(r.x), x);
      EXPECT_EQ(r.shift.x, 0.0f);
      continue;
    }
    EXPECT_EQ(int(r.x), expected_source[x]);
    EXPECT_GT(r.shift.x, -0.5f);
    EXPECT_LE(r.shift.x, 0.5f);
    EXPECT_FLOAT_EQ(r.shift.x, float(expected_source[x] - x) - offsets[x]);
    // The landing point x + 0.5 + b lies in the source's footprint.
    EXPECT_GE(float(x) + 0.5f + offsets[x], float(r.x));
    EXPECT_LT(float(x) + 0.5f + offsets[x], float(r.x + 1));
  }
  // rotate_jitter: frac(u + δ), always inside [0, 1), even for a sum that
  // rounds to 1 after wrapping.
  for (float u : {0.0f, 0.2f, 0.5f, 0.99999994f})
    for (float d : {-0.5f, -0.3f, -1e-9f, 0.0f, 0.3f, 0.5f}) {
      const float v = rotate_unit(u, d);
      EXPECT_GE(v, 0.0f) << u << " " << d;
      EXPECT_LT(v, 1.0f) << u << " " << d;
      const float expect = u + d < 0 ? u + d + 1 : u + d >= 1 ? u + d - 1 : u + d;
      EXPECT_NEAR(v, expect >= 1.0f ? 0.0f : expect, 1e-6f) << u << " " << d;
    }
  // Uniform stays uniform: the rotated positions of a uniform grid are a
  // (wrapped) uniform grid.
  int below_half = 0;
  for (int i = 0; i < 1000; ++i) below_half += rotate_unit((float(i) + 0.5f) / 1000.0f, 0.37f) < 0.5f;
  EXPECT_EQ(below_half, 500);
}

// Synthetic buffers: pass A's primal = 1000·y + x + 0.5 (tells where it was
// read), pass B's = 0; dx, dy alike; variances 1.
LayeredImage pass_buffers(int w, int h, const Image* forward, const Image* backward) {
  LayeredImage L;
  Image a(w, h, 3), zero(w, h, 3), var(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        a.at(x, y, c) = 1000.0f * float(y) + float(x) + 0.5f;
        var.at(x, y, c) = 1.0f;
      }
  for (const char* name : {"primal", "dx", "dy"}) {
    L.add(std::string("a_") + name, kRgb, a);
    L.add(std::string("b_") + name, kRgb, zero);
    L.add(std::string("a_") + name + "_var", kRgb, var);
    L.add(std::string("b_") + name + "_var", kRgb, var);
  }
  L.add("direct", kRgb, zero);
  if (forward) L.add("motion", {"X", "Y", "V"}, *forward);
  if (backward) L.add("motion_back", {"X", "Y", "V"}, *backward);
  return L;
}

TEST(TemporalReplayPairsTest, PairsFollowTheMotionAndDropLeavingTargetsAndInexactRoundTrips) {
  const int w = 8, h = 6;
  // Everything moves 2.4 px right (rounds to 2) and 0.2 px up (0): p's
  // surface lands on q = p + (2, 0), whose backward field (−2.4, 0.2) points
  // back to p.
  Image fwd = uniform_field(w, h, 2.4f, -0.2f);
  Image bwd = uniform_field(w, h, -2.4f, 0.2f);
  fwd.at(1, 1, 2) = 0.0f;   // p = (1, 1): no forward motion (disocclusion)
  bwd.at(5, 3, 0) = -1.4f;  // q = (5, 3) came from (4, 3), not (3, 3): (3, 3) is not its pair
  bwd.at(6, 4, 2) = 0.0f;   // q = (6, 4) has no backward field: (4, 4) drops
  LayeredImage t = pass_buffers(w, h, &fwd, nullptr), next = pass_buffers(w, h, nullptr, &bwd);
  TgptSettings settings;
  ASSERT_TRUE(settings.compensates_motion());
  auto g = temporal_gradients(t, next, settings);
  ASSERT_TRUE(g.ok()) << g.status().to_string();
  ASSERT_EQ(g->target.width(), w);
  ASSERT_EQ(g->target.channels(), 2);
  ASSERT_EQ(g->valid.size(), size_t(w * h));
  int64_t dropped = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      SCOPED_TRACE("pixel " + std::to_string(x) + "," + std::to_string(y));
      const bool leaves = x + 2 >= w;
      const bool keep = !leaves && !(x == 1 && y == 1) && !(x == 3 && y == 3) && !(x == 4 && y == 4);
      EXPECT_EQ(g->valid[size_t(y) * w + x] != 0, keep);
      EXPECT_EQ(g->failure_rate.at(x, y, 0), keep ? 0.0f : 1.0f);
      dropped += !keep;
      if (!keep) {
        EXPECT_EQ(g->target.at(x, y, 0), 0.0f);
        EXPECT_EQ(g->target.at(x, y, 1), 0.0f);
        for (const Image* im : {&g->dt, &g->dxdt, &g->dydt}) EXPECT_EQ(im->at(x, y, 0), 0.0f);
        continue;
      }
      EXPECT_EQ(g->target.at(x, y, 0), 2.0f);
      EXPECT_EQ(g->target.at(x, y, 1), 0.0f);
      // A_{t+1}(q) − B_t(p), read at q = (x + 2, y); variances add.
      const float a_at_q = 1000.0f * float(y) + float(x + 2) + 0.5f;
      for (const Image* im : {&g->dt, &g->dxdt, &g->dydt}) EXPECT_EQ(im->at(x, y, 1), a_at_q);
      for (const Image* im : {&g->dt_var, &g->dxdt_var, &g->dydt_var}) EXPECT_EQ(im->at(x, y, 2), 2.0f);
    }
  EXPECT_EQ(g->failed, dropped);

  // The reconstruction's view carries the target; the same-pixel path none.
  TemporalGradients tg = std::move(g.value());
  auto gf = tgpt_gradient_frame(t, &tg);
  ASSERT_TRUE(gf.ok()) << gf.status().to_string();
  EXPECT_EQ(gf->temporal_target.width(), w);
  EXPECT_EQ(gf->temporal_target.at(0, 0, 0), 2.0f);

  // Off (or with motion vectors off, or reconnect): the same-pixel pairs,
  // as before, with no target. A 2.4 px motion exceeds the same-pixel limit.
  for (int variant = 0; variant < 2; ++variant) {
    TgptSettings same = settings;
    if (variant == 0) same.motion_compensation = false;
    else same.motion_vectors = false;
    EXPECT_FALSE(same.compensates_motion());
    auto s = temporal_gradients(t, next, same);
    ASSERT_TRUE(s.ok()) << s.status().to_string();
    EXPECT_TRUE(s->target.empty());
    EXPECT_EQ(s->dt.at(3, 2, 0), variant == 0 ? 0.0f : 1000.0f * 2 + 3 + 0.5f);
    auto sf = tgpt_gradient_frame(t, &s.value());
    ASSERT_TRUE(sf.ok());
    EXPECT_TRUE(sf->temporal_target.empty());
  }
  TgptSettings reconnect = settings;
  reconnect.temporal_shift = TemporalShiftMapping::kReconnect;
  EXPECT_FALSE(reconnect.compensates_motion());
}

// A crop of the buffers (a tile's region): pairs whose q leaves the crop drop,
// the others are those of the whole frame.
TEST(TemporalReplayPairsTest, ACropDropsPairsLeavingIt) {
  const int w = 10, h = 4;
  Image fwd = uniform_field(w, h, -1.2f, 0.0f), bwd = uniform_field(w, h, 1.2f, 0.0f);
  ReplayPairs whole = replay_pairs(fwd, bwd);
  auto crop = [](const Image& im, int x0, int x1) {
    Image out(x1 - x0, im.height(), im.channels());
    for (int y = 0; y < im.height(); ++y)
      for (int x = x0; x < x1; ++x)
        for (int c = 0; c < im.channels(); ++c) out.at(x - x0, y, c) = im.at(x, y, c);
    return out;
  };
  ReplayPairs part = replay_pairs(crop(fwd, 4, 8), crop(bwd, 4, 8));
  for (int y = 0; y < h; ++y) {
    EXPECT_FALSE(whole.valid[size_t(y) * w + 0]);  // lands at x = −1
    EXPECT_FALSE(part.valid[size_t(y) * 4 + 0]);   // lands left of the crop
    for (int x = 5; x < 8; ++x) {
      EXPECT_TRUE(part.valid[size_t(y) * 4 + size_t(x - 4)]);
      EXPECT_TRUE(whole.valid[size_t(y) * w + x]);
      EXPECT_EQ(part.target.at(x - 4, y, 0), -1.0f);
    }
  }
}

// ---------------------------------------------------------------------------
// A camera pan over a fine checkerboard
// ---------------------------------------------------------------------------

constexpr int kRes = 24;

// A diffuse plane with a checkerboard of ~0.7 px squares facing the camera
// under a uniform sky: its radiance is the albedo, so everything dt sees is
// the texture under the pixel and the sky sampling, which the replay shares.
const char* kCheckerPlaneXml = R"(<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/>
      <rfilter type="box"/></film>
  </sensor>
  <texture type="checkerboard" id="fine">
    <rgb name="color0" value="0.9, 0.8, 0.7"/>
    <rgb name="color1" value="0.1, 0.15, 0.2"/>
    <transform name="to_uv"><scale x="60" y="60"/></transform>
  </texture>
  <shape type="rectangle">
    <transform name="to_world"><scale x="2" y="2"/></transform>
    <bsdf type="diffuse"><ref name="reflectance" id="fine"/></bsdf>
  </shape>
  <emitter type="constant"><rgb name="radiance" value="1, 1, 1"/></emitter>
</scene>)";

// World units per pixel on the plane (distance 1, 60° horizontal field).
const float kPixelWorld = 2.0f * std::tan(30.0f * 3.14159265f / 180.0f) / float(kRes);

struct PanPair {
  Scene at[2];
  std::unique_ptr<FrameScene> scene[2];
};

// Frame 0 and frame 1, the camera moved sideways by `px` pixels (the image
// moves the other way) and `py` pixels up.
std::unique_ptr<PanPair> pan_pair(float px, float py) {
  auto desc = load_mitsuba_scene_from_string(kCheckerPlaneXml, ".", {});
  EXPECT_TRUE(desc.ok()) << desc.status().to_string();
  if (!desc.ok()) return nullptr;
  auto pair = std::make_unique<PanPair>();
  pair->at[0] = desc.value();
  pair->at[1] = desc.value();
  pair->at[1].camera.to_world =
      Transform::translate({px * kPixelWorld, py * kPixelWorld, 0.0f}) * pair->at[0].camera.to_world;
  for (int f : {0, 1}) {
    auto fs = FrameScene::create(pair->at[f], {});
    EXPECT_TRUE(fs.ok());
    if (!fs.ok()) return nullptr;
    pair->scene[f] = std::move(fs.value());
  }
  return pair;
}

FrameRenderSettings pan_render(int spp, uint64_t seed) {
  FrameRenderSettings rs;
  rs.width = rs.height = kRes;
  rs.spp = spp;
  rs.seed = seed;
  rs.threads = 2;
  rs.tile_size = 8;
  rs.path.max_depth = 3;
  return rs;
}

// Stage 1 of both frames (frame 0 as the shot's first, frame 1 as its last)
// and stage 2 with `settings`, which also renders frame 1's pass A.
Expected<TemporalGradients> pan_gradients(const PanPair& pair, const FrameRenderSettings& rs,
                                          const TgptSettings& settings) {
  const FramePairChanges changes = detect_changes(pair.at[0], pair.at[1]);
  TgptNeighbourhood nb0, nb1;
  nb0.at_t = &pair.at[0];
  nb0.next = &pair.at[1];
  nb0.to_next = changes;
  nb1.at_t = &pair.at[1];
  nb1.prev = &pair.at[0];
  nb1.to_prev = changes;
  auto f0 = render_tgpt_frame(*pair.scene[0], rs, settings, {0, 1}, nb0, nullptr, {});
  if (!f0.ok()) return f0.status();
  auto f1 = render_tgpt_frame(*pair.scene[1], rs, settings, {1, 2}, nb1, nullptr, {});
  if (!f1.ok()) return f1.status();
  LayeredImage l0 = tgpt_frame_layers(std::move(f0.value())), l1 = tgpt_frame_layers(std::move(f1.value()));
  return temporal_gradients(l0, l1, settings);
}

TgptSettings pan_settings(bool compensate) {
  TgptSettings s;
  s.motion_compensation = compensate;
  s.max_same_pixel_motion_px = -1;  // compare both on every pixel whose surface stays in view
  return s;
}

// The replay map on a pan: sources one rounded motion away, shifts in (−0.5, 0.5].
TEST(TemporalReplayMapTest, PanMapsEveryInnerPixelToItsSource) {
  auto pair = pan_pair(1.3f, 0.0f);
  ASSERT_TRUE(pair);
  MotionField back = compute_motion_field(*pair->scene[1], pair->at[1], pair->at[0], kRes, kRes, 2);
  ReplayMap map = build_replay_map(back.offsets);
  int moved = 0;
  for (int y = 0; y < kRes; ++y)
    for (int x = 0; x < kRes; ++x) {
      const ReplaySource& r = map.at(x, y);
      EXPECT_GT(r.shift.x, -0.5f - 1e-6f);
      EXPECT_LE(r.shift.x, 0.5f + 1e-6f);
      EXPECT_EQ(int(r.y), y);
      // The camera moved 1.3 px right: frame 1's pixel q saw its surface at q + 1.3 in frame 0.
      if (x + 1 < kRes) {
        EXPECT_EQ(int(r.x), x + 1) << x << "," << y;
        EXPECT_NEAR(r.shift.x, -0.3f, 0.02f) << x << "," << y;
        ++moved;
      }
    }
  EXPECT_GT(moved, 0);
}

// Motion compensation on a pan: the replayed pair follows the surface, so dt
// keeps the correlation a same-pixel pair loses once the texture under the
// pixel changes. Empirical variance of dt over seeds, both on the same pixels.
// The compensated pair decorrelates only where u + δ wraps, a fraction |δ| of
// the samples (δ = round(m) − m), so the gain is largest where the motion is
// near whole pixels; on this 0.7-pixel checkerboard it measured 2.7x at
// 0.3 px per frame (δ = 0.3), 6.0x at 0.7, 7.5x at 1.1 and 12.6x at 1.9. (On
// textures coarser than a pixel a motion below half a pixel gains nothing:
// the same-pixel pair then decorrelates about as often, e.g. 0.94-0.99x at
// 0.3 px on 2- and 4-pixel squares.)
TEST(TemporalMotionCompensationTest, PanOverTextureHasFarLessNoisyDt) {
  constexpr int kSeeds = 8;
  const std::pair<float, double> cases[] = {{0.3f, 1.8}, {0.7f, 4.0}, {1.1f, 5.0}, {1.9f, 8.0}};
  for (auto [motion, min_factor] : cases) {
    auto pair = pan_pair(motion, 0.0f);
    ASSERT_TRUE(pair);
    const size_t n = size_t(kRes) * kRes * 3;
    std::vector<double> sum[2], sum_sq[2];
    std::vector<uint8_t> both(size_t(kRes) * kRes, 1);
    for (int mode : {0, 1}) {
      sum[mode].assign(n, 0.0);
      sum_sq[mode].assign(n, 0.0);
      for (int s = 0; s < kSeeds; ++s) {
        auto g = pan_gradients(*pair, pan_render(8, 31 + 977 * uint64_t(s)), pan_settings(mode == 1));
        ASSERT_TRUE(g.ok()) << g.status().to_string();
        for (size_t p = 0; p < both.size(); ++p)
          if (!g->valid.empty() && !g->valid[p]) both[p] = 0;
        for (size_t k = 0; k < n; ++k) {
          sum[mode][k] += g->dt.data()[k];
          sum_sq[mode][k] += double(g->dt.data()[k]) * g->dt.data()[k];
        }
      }
    }
    double var[2] = {0, 0};
    int count = 0;
    for (size_t p = 0; p < both.size(); ++p) {
      if (!both[p]) continue;
      ++count;
      for (int mode : {0, 1})
        for (int c = 0; c < 3; ++c) {
          const size_t k = p * 3 + size_t(c);
          const double mean = sum[mode][k] / kSeeds;
          var[mode] += std::max(0.0, (sum_sq[mode][k] - kSeeds * mean * mean) / (kSeeds - 1));
        }
    }
    ASSERT_GT(count, kRes * kRes / 2) << motion;
    const double factor = var[0] / std::max(var[1], 1e-30);
    std::printf("[ motion compensation ] pan %.1f px: Var dt same-pixel %.3g, compensated %.3g (%.1fx lower), %d px\n",
                motion, var[0] / count, var[1] / count, factor, count);
    EXPECT_GT(factor, min_factor) << "pan of " << motion << " px";
  }
}

// Unbiasedness: the mean over seeds of the compensated dt, dxdt, dydt at p
// equals I_1(q) − I_0(p) (and the spatial differences likewise) of converged
// PT frames, q = p + target(p). The rotated sub-pixel position keeps pass A
// uniform over q's footprint; a footprint shifted by δ would show as a
// per-pixel bias on this texture.
TEST(TemporalMotionCompensationTest, CompensatedGradientsMatchConvergedFrames) {
  auto pair = pan_pair(0.7f, -0.4f);
  ASSERT_TRUE(pair);
  Image ref[2], ref_var[2];
  for (int f : {0, 1}) {
    auto r = render_frame_pt(*pair->scene[f], pan_render(1024, 4242 + uint64_t(f)), 0, {});
    ASSERT_TRUE(r.ok()) << r.status().to_string();
    ref[f] = r->color;
    for (size_t k = 0; k < ref[f].data().size(); ++k) ref[f].data()[k] -= r->direct.data()[k];
    ref_var[f] = r->variance;
  }
  constexpr int kSeeds = 12;
  const size_t n = size_t(kRes) * kRes * 3;
  std::vector<double> sum(3 * n, 0.0), sum_sq(3 * n, 0.0);
  Image target;
  std::vector<uint8_t> valid;
  for (int s = 0; s < kSeeds; ++s) {
    auto g = pan_gradients(*pair, pan_render(8, 7 + 1543 * uint64_t(s)), pan_settings(true));
    ASSERT_TRUE(g.ok()) << g.status().to_string();
    ASSERT_FALSE(g->target.empty());
    if (s == 0) {
      target = g->target;
      valid = g->valid;
    }
    EXPECT_EQ(g->valid, valid) << "the pairs depend on the geometry only";
    const Image* terms[3] = {&g->dt, &g->dxdt, &g->dydt};
    for (int t = 0; t < 3; ++t)
      for (size_t k = 0; k < n; ++k) {
        sum[size_t(t) * n + k] += terms[t]->data()[k];
        sum_sq[size_t(t) * n + k] += double(terms[t]->data()[k]) * terms[t]->data()[k];
      }
  }
  for (int t = 0; t < 3; ++t) {
    test::SeedMeanZ z;
    for (int y = 0; y < kRes; ++y)
      for (int x = 0; x < kRes; ++x) {
        if (!valid[size_t(y) * kRes + x]) continue;
        const int qx = x + int(target.at(x, y, 0)), qy = y + int(target.at(x, y, 1));
        const int ex = t == 1, ey = t == 2;  // dxdt, dydt: the neighbour at +x, +y
        if (x + ex >= kRes || y + ey >= kRes || qx + ex >= kRes || qy + ey >= kRes) continue;
        for (int c = 0; c < 3; ++c) {
          double fd = ref[1].at(qx + ex, qy + ey, c) - ref[0].at(x + ex, y + ey, c);
          double fd_var = ref_var[1].at(qx + ex, qy + ey, c) + ref_var[0].at(x + ex, y + ey, c);
          if (t > 0) {
            fd -= ref[1].at(qx, qy, c) - ref[0].at(x, y, c);
            fd_var += ref_var[1].at(qx, qy, c) + ref_var[0].at(x, y, c);
          }
          const size_t k = size_t(t) * n + (size_t(y) * kRes + size_t(x)) * 3 + size_t(c);
          z.add(sum[k], sum_sq[k], kSeeds, fd, fd_var);
        }
      }
    std::printf("[ motion compensation ] %s: mean z^2 %.3f over %d, aggregate z %.2f\n",
                t == 0 ? "dt" : t == 1 ? "dxdt" : "dydt", z.mean_z2(), z.count, z.aggregate_z());
    ASSERT_GT(z.count, kRes * kRes);
    // Student t with 11 dof: E[z^2] = 11/9; a biased estimator shows as a clear excess.
    EXPECT_LT(z.mean_z2(), 1.8);
    EXPECT_LT(std::abs(z.aggregate_z()), 4.5);
  }
}

// The map reaches the tracer and nothing else changes: an identity map (every
// pixel its own stream, unrotated) renders the frame bit for bit as no map,
// and a real map changes pass A only where it moves a pixel's source.
TEST(GptReplayMapTest, IdentityMapIsBitIdenticalToNoMap) {
  auto pair = pan_pair(1.3f, 0.0f);
  ASSERT_TRUE(pair);
  const FrameRenderSettings rs = pan_render(4, 99);
  const GptSettings gpt = TgptSettings::gpt_defaults_for(kDefaultShiftMapping);
  ReplayMap identity = build_replay_map(Image(kRes, kRes, 3));  // V = 0 everywhere: own streams
  auto plain = render_frame_gpt(*pair->scene[1], rs, gpt, 5, {});
  auto same = render_frame_gpt(*pair->scene[1], rs, gpt, 5, {}, nullptr, &identity);
  ASSERT_TRUE(plain.ok() && same.ok());
  const std::pair<const Image*, const Image*> layers[] = {
      {&plain->buffers.primal, &same->buffers.primal},
      {&plain->buffers.dx, &same->buffers.dx},
      {&plain->buffers.dy, &same->buffers.dy},
      {&plain->buffers.primal_var, &same->buffers.primal_var},
      {&plain->buffers.dx_var, &same->buffers.dx_var}};
  for (auto [a, b] : layers) EXPECT_EQ(a->data(), b->data());
  // A map whose size is not the frame's is refused.
  ReplayMap small = build_replay_map(Image(kRes - 1, kRes, 3));
  EXPECT_FALSE(render_frame_gpt(*pair->scene[1], rs, gpt, 5, {}, nullptr, &small).ok());
  // The pan's map: pixels replaying another pixel's stream differ.
  MotionField back = compute_motion_field(*pair->scene[1], pair->at[1], pair->at[0], kRes, kRes, 2);
  ReplayMap map = build_replay_map(back.offsets);
  auto moved = render_frame_gpt(*pair->scene[1], rs, gpt, 5, {}, nullptr, &map);
  ASSERT_TRUE(moved.ok());
  EXPECT_NE(moved->buffers.primal.data(), plain->buffers.primal.data());
}

}  // namespace
}  // namespace gdvr
