// Motion-compensated temporal terms (core/recon/temporal_targets.h): the
// operator, right-hand side and diagonal against the normal equations built
// explicitly, the same-pixel case against the stencil, and the solvers on a
// panning window with a known answer.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "core/recon/constraint_layout.h"
#include "core/recon/poisson_kernels.h"
#include "core/recon/poisson_operator.h"
#include "core/recon/reconstruct.h"
#include "core/recon/tiled_reconstruct.h"
#include "recon_test_scene.h"

namespace gdvr {
namespace {

constexpr Term kTemporalTermsInOrder[3] = {Term::kDt, Term::kDxdt, Term::kDydt};

// A small window with random targets (some off the image, some colliding),
// random masks and random per-constraint float weights.
struct RandomWindow {
  GradientWindow window;
  ConstraintLayout layout;
};

// `scattered`: the share of pixels with a random offset in [−2, 2]²; the
// others move with the frame's pan ((t % 3) − 1, 1 − (t % 2)), as a camera
// pan does, so that most blocks of a line share one offset
// (classify_target_blocks) and the operator reads them as vectors.
RandomWindow random_window(unsigned seed, int w = 9, int h = 7, int frames = 4, double scattered = 1.0) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> offset(-2, 2);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  RandomWindow r;
  for (int t = 0; t < frames; ++t) {
    auto f = std::make_shared<GradientFrame>();
    for (Term term : kAllTerms) {
      f->buffer(term) = Image(w, h, 1);
      for (float& v : f->buffer(term).data()) v = u(rng) - 0.5f;
    }
    f->temporal_target = Image(w, h, 2);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const bool random = u(rng) < scattered;
        f->temporal_target.at(x, y, 0) = float(random ? offset(rng) : (t % 3) - 1);
        f->temporal_target.at(x, y, 1) = float(random ? offset(rng) : 1 - (t % 2));
      }
    std::vector<uint8_t> mask(size_t(w) * h);
    for (auto& m : mask) m = u(rng) < 0.85f;
    for (Term term : {Term::kDt, Term::kDxdt, Term::kDydt}) f->mask(term) = mask;
    r.window.frames.push_back(std::move(f));
  }
  r.layout = build_constraint_layout(r.window);
  return r;
}

// Row of H_term at pixel i as (index, coefficient) pairs, from the definition.
std::vector<std::pair<size_t, float>> constraint_row(const Grid& g, const TemporalTargets& to, Term term, size_t i) {
  const size_t sx = 1, sy = size_t(g.width);
  switch (term) {
    case Term::kPrimal: return {{i, 1.0f}};
    case Term::kDx: return {{i + sx, 1.0f}, {i, -1.0f}};
    case Term::kDy: return {{i + sy, 1.0f}, {i, -1.0f}};
    default: break;
  }
  const size_t j = size_t(int64_t(i) + int64_t(g.frame_size()) + to.next_offset[i]);
  if (term == Term::kDt) return {{j, 1.0f}, {i, -1.0f}};
  const size_t s = term == Term::kDxdt ? sx : sy;
  return {{j + s, 1.0f}, {j, -1.0f}, {i + s, -1.0f}, {i, 1.0f}};
}

TEST(TemporalTargetsTest, TargetsAreOneToOneAndInsideTheImage) {
  const RandomWindow r = random_window(3);
  const Grid& g = r.layout.grid;
  const TemporalTargets& to = r.layout.targets;
  ASSERT_FALSE(to.empty());
  std::vector<int> hits(g.size(), 0);
  int64_t lands = 0;
  for (size_t i = 0; i < g.size(); ++i) {
    if (!to.lands(i)) continue;
    ++lands;
    const int64_t j = int64_t(i) + int64_t(g.frame_size()) + to.next_offset[i];
    ASSERT_GE(j, int64_t(g.frame_size()));
    ASSERT_LT(j, int64_t(g.size()));
    EXPECT_EQ(++hits[size_t(j)], 1) << "two sources land on pixel " << j;
    EXPECT_EQ(to.prev_source[size_t(j)], int32_t(i));
    // The frame's own offset, not another one.
    const int t = int(i / g.frame_size()), p = int(i % g.frame_size());
    const Image& target = r.window.frames[size_t(t)]->temporal_target;
    const int q = int(j - int64_t(g.frame_size()) * (t + 1));
    EXPECT_EQ(q % g.width - p % g.width, int(target.at(p % g.width, p / g.width, 0)));
    EXPECT_EQ(q / g.width - p / g.width, int(target.at(p % g.width, p / g.width, 1)));
  }
  EXPECT_GT(lands, int64_t(g.size()) / 3);
  // Collisions and targets off the image drop constraints, counted as masked.
  EXPECT_GT(r.layout.masked[term_index(Term::kDt)], 0);
  for (size_t i = 0; i < g.size(); ++i) {
    if (r.layout.mask(Term::kDt)[i]) {
      EXPECT_TRUE(to.lands(i));
    }
  }
}

// Where few constraints leave their pixel, those few are dropped and the
// rest stay with the stencil (kMinMovingShare).
TEST(TemporalTargetsTest, AFewMovingConstraintsAreDroppedForTheStencil) {
  RandomWindow r = random_window(7);
  const int w = r.window.width(), h = r.window.height();
  // Every offset zero but two pixels of frame 1: 2 of 189 sources move.
  for (int t = 0; t < r.window.size(); ++t) {
    GradientFrame& f = test::mutable_frame(r.window, t);
    for (float& v : f.temporal_target.data()) v = 0.0f;
    for (Term term : {Term::kDt, Term::kDxdt, Term::kDydt}) f.mask(term).assign(size_t(w) * h, 1);
  }
  test::mutable_frame(r.window, 1).temporal_target.at(2, 3, 0) = 1.0f;
  test::mutable_frame(r.window, 1).temporal_target.at(5, 1, 1) = -1.0f;
  const ConstraintLayout layout = build_constraint_layout(r.window);
  EXPECT_TRUE(layout.targets.all_same_pixel);
  EXPECT_TRUE(layout.targets.empty());  // the solvers take the stencil
  const Grid& g = layout.grid;
  for (Term term : {Term::kDt, Term::kDxdt, Term::kDydt}) {
    EXPECT_EQ(layout.mask(term)[g.index(2, 3, 1)], 0) << term_name(term);
    EXPECT_EQ(layout.mask(term)[g.index(5, 1, 1)], 0) << term_name(term);
    EXPECT_EQ(layout.mask(term)[g.index(2, 3, 0)], 1) << term_name(term);
    EXPECT_EQ(layout.masked[term_index(term)], 2) << term_name(term);
  }
  // Exactly the stencil's system with those two constraints masked by the caller.
  GradientWindow masked = r.window;
  for (auto& frame : masked.frames) {
    auto copy = std::make_shared<GradientFrame>(*frame);
    copy->temporal_target = Image();
    frame = copy;
  }
  for (Term term : {Term::kDt, Term::kDxdt, Term::kDydt}) {
    GradientFrame& f = test::mutable_frame(masked, 1);
    f.mask(term)[size_t(3) * w + 2] = 0;
    f.mask(term)[size_t(1) * w + 5] = 0;
  }
  const ConstraintLayout expected = build_constraint_layout(masked);
  for (Term term : kAllTerms) EXPECT_EQ(layout.mask(term), expected.mask(term)) << term_name(term);
}

// A, b and diag(A) of both weight modes of r's system equal Hᵀ W H etc.
// assembled from the definitions.
void expect_normal_equations(const RandomWindow& r, unsigned seed) {
  ASSERT_FALSE(r.layout.targets.empty()) << "the window must follow motion for this check";
  const Grid& g = r.layout.grid;
  std::mt19937 rng(seed + 100);
  std::uniform_real_distribution<float> u(0.1f, 1.0f);
  // Float mode: random positive weights on valid constraints.
  PoissonSystem float_mode(g, true);
  float_mode.follow_temporal_targets(&r.layout.targets);
  for (Term term : kAllTerms)
    for (size_t i = 0; i < g.size(); ++i) float_mode.weights(term)[i] = r.layout.mask(term)[i] ? u(rng) : 0.0f;
  // Mask mode: constant weights per term.
  const std::array<float, kTermCount> term_w = {0.04f, 1.0f, 0.8f, 0.6f, 0.5f, 0.3f};
  PoissonSystem mask_mode(g, true, term_w, 0.001f, pack_valid_bits(r.layout));
  mask_mode.follow_temporal_targets(&r.layout.targets);

  std::vector<float> p(g.size());
  for (float& v : p) v = u(rng) - 0.5f;
  std::array<Field, kTermCount> d;
  std::array<const Field*, kTermCount> targets{};
  for (Term term : kAllTerms) {
    d[term_index(term)] = gather_term(r.window, r.layout, term, 0);
    targets[term_index(term)] = &d[term_index(term)];
  }
  for (const PoissonSystem* A : {&float_mode, &mask_mode}) {
    const bool masked = A == &mask_mode;
    const auto weight = [&](Term term, size_t i) -> double {
      const bool valid = r.layout.mask(term)[i] != 0;
      if (!masked) return A->weights(term)[i];
      if (term == Term::kPrimal) return valid ? term_w[0] : 0.001;
      return valid ? term_w[size_t(term_index(term))] : 0.0;
    };
    std::vector<double> Ap(g.size(), 0.0), b(g.size(), 0.0), diag(g.size(), 0.0);
    for (Term term : kAllTerms)
      for (size_t i = 0; i < g.size(); ++i) {
        const double w = weight(term, i);
        if (w == 0.0 || (term != Term::kPrimal && !r.layout.mask(term)[i])) continue;
        const auto row = constraint_row(g, r.layout.targets, term, i);
        double h = 0;
        for (auto [k, c] : row) h += c * p[k];
        const double target = term == Term::kPrimal && !r.layout.mask(term)[i] ? 0.0 : d[term_index(term)][i];
        for (auto [k, c] : row) {
          Ap[k] += w * c * h;
          b[k] += w * c * target;
          diag[k] += w * c * c;
        }
      }
    Field q(g.size()), got_b, got_diag;
    const double pq = A->apply(p.data(), q.data());
    A->rhs(targets, &got_b);
    A->diagonal(&got_diag);
    double want_pq = 0;
    for (size_t i = 0; i < g.size(); ++i) {
      EXPECT_NEAR(q[i], Ap[i], 1e-4) << "A p at " << i << (masked ? " (mask mode)" : " (float mode)");
      EXPECT_NEAR(got_b[i], b[i], 1e-4) << "b at " << i;
      EXPECT_NEAR(got_diag[i], diag[i], 1e-4) << "diag at " << i;
      want_pq += p[i] * Ap[i];
    }
    EXPECT_NEAR(pq, want_pq, 1e-3);
  }
}

// On scattered offsets (read one by one), on a pan with a few scattered ones
// (mostly read as vectors, with holes and collisions), and on windows one or
// two pixels wide or high (blocks shorter than a vector, or none).
TEST(TemporalTargetsTest, OperatorRhsAndDiagonalMatchTheNormalEquations) {
  for (unsigned seed : {1u, 2u, 5u}) expect_normal_equations(random_window(seed), seed);
  for (unsigned seed : {6u, 7u}) expect_normal_equations(random_window(seed, 71, 9, 4, 0.05), seed);
  const int shapes[][2] = {{1, 6}, {2, 5}, {6, 1}, {10, 2}, {19, 3}};
  unsigned seed = 20;
  for (const auto& wh : shapes) {
    SCOPED_TRACE(std::to_string(wh[0]) + "x" + std::to_string(wh[1]));
    ++seed;
    expect_normal_equations(random_window(seed, wh[0], wh[1], 3, 0.5), seed);
  }
}

// Each block the classification lets the operator read as vectors does share
// one offset: checked against the map pixel by pixel; on a pan most do.
TEST(TemporalTargetsTest, ContiguousBlocksShareTheirOffsets) {
  const RandomWindow r = random_window(8, 71, 9, 4, 0.05);
  const Grid& g = r.layout.grid;
  const TemporalTargets& to = r.layout.targets;
  const TemporalTargetBlocks blocks = classify_target_blocks(g, to);
  ASSERT_EQ(blocks.per_line, (70 + kTargetBlock - 1) / kTargetBlock);  // columns 1..70
  const int64_t W = g.width, size = int64_t(g.size());
  int contiguous_next = 0, contiguous_source = 0, forward_blocks = 0;
  for (int row = 0; row < g.rows(); ++row) {
    const bool forward = row / g.height < g.frames - 1, up = row % g.height != 0;
    for (int b = 0; b < blocks.per_line; ++b) {
      const size_t at = size_t(row) * size_t(blocks.per_line) + size_t(b);
      const int64_t c0 = 1 + int64_t(b) * kTargetBlock, c1 = std::min<int64_t>(W, c0 + kTargetBlock);
      forward_blocks += forward;
      if (!forward) {
        EXPECT_EQ(blocks.next[at], kScatteredBlock) << "the last frame has no targets";
      }
      if (const int32_t o = blocks.next[at]; forward && o != kScatteredBlock) {
        ++contiguous_next;
        for (int64_t c = c0; c < c1; ++c) {
          const int64_t n = int64_t(row) * W + c, j = n + int64_t(g.frame_size()) + o;
          if (to.lands(size_t(n))) {
            EXPECT_EQ(to.next_offset[size_t(n)], o) << "row " << row << " column " << c;
          }
          EXPECT_GE(j, 0);
          EXPECT_LE(j + W, size - 1);
        }
      }
      if (const int32_t d = blocks.source[at]; d != kScatteredBlock) {
        ++contiguous_source;
        for (int64_t c = c0; c < c1; ++c) {
          const int64_t n = int64_t(row) * W + c;
          for (int64_t m : {n, n - 1, up ? n - W : n}) {
            if (to.prev_source[size_t(m)] >= 0) {
              EXPECT_EQ(to.prev_source[size_t(m)], m - d) << "pixel " << m;
            }
            EXPECT_GE(m - d, 0);
            EXPECT_LT(m - d, size);
          }
        }
      }
    }
  }
  EXPECT_GT(contiguous_next, forward_blocks / 2);
  EXPECT_GT(contiguous_source, g.rows() * blocks.per_line / 2);
}

// The motion-following passes of every instruction-set variant give the
// baseline's bits, on a pan with scattered offsets, holes and collisions.
TEST(TemporalTargetsTest, KernelVariantsGiveTheBaselineBits) {
  const auto variants = poisson_kernel_variants();
  const RandomWindow r = random_window(9, 83, 9, 4, 0.05);
  const Grid& g = r.layout.grid;
  const TemporalTargets& to = r.layout.targets;
  const TemporalTargetBlocks blocks = classify_target_blocks(g, to);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Field x(g.size()), weights(3 * g.size()), h(3 * g.size());
  for (float& v : x) v = u(rng);
  for (size_t k = 0; k < 3; ++k)
    for (size_t i = 0; i < g.size(); ++i)
      weights[k * g.size() + i] = r.layout.mask(kTemporalTermsInOrder[k])[i] ? 0.5f + 0.5f * u(rng) : 0.0f;
  for (float& v : h) v = u(rng);
  const std::vector<uint8_t> bits = pack_valid_bits(r.layout);
  const size_t last_frame = size_t(g.frames - 1) * g.frame_size();
  const auto run = [&](const PoissonKernels& k, bool masked, std::vector<float>* forward, std::vector<float>* out,
                       float* dot) {
    forward->assign(3 * g.size(), 7.0f);
    out->assign(g.size(), 0.5f);
    *dot = 0;
    std::vector<float> v(size_t(g.width));
    for (int row = 0; row < g.rows(); ++row) {
      const int64_t begin = int64_t(row) * g.width;
      if (size_t(begin) < last_frame) {
        TemporalForwardLine f;
        f.x = x.data();
        f.begin = begin;
        f.width = g.width;
        f.frame_size = int64_t(g.frame_size());
        f.last = int64_t(g.size()) - 1;
        f.next_offset = to.next_offset.data() + begin;
        f.block_offset = blocks.next.data() + size_t(row) * size_t(blocks.per_line);
        f.masked = masked;
        f.bits = bits.data() + begin;
        for (size_t t = 0; t < 3; ++t) {
          f.term_weight[t] = 0.25f * float(t + 1);
          f.weight[t] = weights.data() + t * g.size() + size_t(begin);
          f.h[t] = forward->data() + t * g.size() + size_t(begin);
        }
        k.temporal_forward_line(f);
      }
      TemporalAdjointLine a;
      for (size_t t = 0; t < 3; ++t) a.h[t] = h.data() + t * g.size();
      a.begin = begin;
      a.width = g.width;
      a.up = row % g.height != 0;
      a.prev_source = to.prev_source.data();
      a.block_source = blocks.source.data() + size_t(row) * size_t(blocks.per_line);
      a.minus = masked ? 1.0f : -1.0f;
      a.v = v.data();
      a.out = out->data() + begin;
      a.dot_with = x.data() + begin;
      *dot += k.temporal_adjoint_line(a);
    }
  };
  int compared = 0;
  for (bool masked : {true, false}) {
    std::vector<float> f_base, o_base;
    float dot_base;
    run(*variants.front(), masked, &f_base, &o_base, &dot_base);
    ASSERT_TRUE(std::isfinite(dot_base));
    ASSERT_NE(f_base[size_t(g.width) + 5], 7.0f) << "the forward pass wrote nothing";
    for (size_t v = 1; v < variants.size(); ++v) {
      std::vector<float> f, o;
      float dot;
      run(*variants[v], masked, &f, &o, &dot);
      SCOPED_TRACE(std::string(variants[v]->isa) + (masked ? " masked" : " float weights"));
      EXPECT_EQ(std::memcmp(&dot, &dot_base, sizeof dot), 0) << dot << " vs " << dot_base;
      EXPECT_EQ(std::memcmp(f.data(), f_base.data(), f.size() * sizeof(float)), 0);
      EXPECT_EQ(std::memcmp(o.data(), o_base.data(), o.size() * sizeof(float)), 0);
      ++compared;
    }
  }
  EXPECT_EQ(compared, 2 * int(variants.size() - 1));
}

// Zero offsets through the motion path give what the same-pixel stencil gives.
TEST(TemporalTargetsTest, SamePixelTargetsReproduceTheStencil) {
  test::SceneOptions o;
  o.frames = 4;
  o.temporal = true;
  o.width = 23;
  o.height = 17;
  const GradientWindow w = test::make_window(o);
  const ConstraintLayout layout = build_constraint_layout(w);
  ASSERT_TRUE(layout.targets.empty());
  const Grid& g = layout.grid;
  TemporalTargets same;
  same.next_offset.assign(g.size(), 0);
  same.prev_source.assign(g.size(), -1);
  for (size_t i = g.frame_size(); i < g.size(); ++i) same.prev_source[i] = int32_t(i - g.frame_size());
  for (size_t i = (g.frames - 1) * g.frame_size(); i < g.size(); ++i) same.next_offset[i] = TemporalTargets::kNone;
  const std::array<float, kTermCount> term_w = {0.04f, 1.0f, 1.0f, 0.7f, 0.5f, 0.5f};
  PoissonSystem stencil(g, true, term_w, 0.001f, pack_valid_bits(layout));
  PoissonSystem gather(g, true, term_w, 0.001f, pack_valid_bits(layout));
  gather.follow_temporal_targets(&same);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Field p(g.size()), q1(g.size()), q2(g.size()), d1, d2;
  for (float& v : p) v = u(rng);
  EXPECT_NEAR(stencil.apply(p.data(), q1.data()), gather.apply(p.data(), q2.data()), 1e-3);
  stencil.diagonal(&d1);
  gather.diagonal(&d2);
  for (size_t i = 0; i < g.size(); ++i) {
    EXPECT_NEAR(q1[i], q2[i], 1e-5) << i;
    EXPECT_NEAR(d1[i], d2[i], 1e-6) << i;
  }
}

// On a pan of 2 px per frame, temporal terms that follow the motion are exact;
// with exact gradients every solver returns the exact frames, and with a noisy
// primal the window does better than its frames solved alone.
class TemporalTargetsSolveTest : public ::testing::TestWithParam<ReconMethod> {
 protected:
  ReconSettings settings() const {
    ReconSettings s;
    s.method = GetParam();
    s.l2_tolerance = 1e-6;
    s.l2_max_iterations = 1000;
    s.cv_iterations = 300;
    return s;
  }
  static test::SceneOptions pan() {
    test::SceneOptions o;
    o.frames = 5;
    o.temporal = true;
    o.variances = true;
    o.pan_x = 2;
    o.pan_y = -1;
    o.follow_motion = true;
    return o;
  }
};

TEST_P(TemporalTargetsSolveTest, ExactBuffersGiveTheExactPan) {
  const test::SceneOptions o = pan();
  const GradientWindow w = test::make_window(o);
  auto r = reconstruct(w, settings());
  ASSERT_TRUE(r.ok()) << r.status().to_string();
  for (int t = 0; t < o.frames; ++t)
    EXPECT_LT(test::frame_error(r->frames[size_t(t)], t, o.pan_x, o.pan_y).max, 2e-3) << "frame " << t;
}

TEST_P(TemporalTargetsSolveTest, FollowingTheMotionBeatsSolvingFramesAlone) {
  test::SceneOptions o = pan();
  o.primal_sigma = 0.1f;
  GradientWindow w = test::make_window(o);
  test::mark_gradients_exact(w);
  auto joint = reconstruct(w, settings());
  ASSERT_TRUE(joint.ok()) << joint.status().to_string();
  double joint_rms = 0, alone_rms = 0;
  for (int t = 0; t < o.frames; ++t) {
    auto alone = reconstruct(GradientWindow{{w.frames[size_t(t)]}}, settings());
    ASSERT_TRUE(alone.ok());
    joint_rms += test::frame_error(joint->frames[size_t(t)], t, o.pan_x, o.pan_y).rms;
    alone_rms += test::frame_error(alone->frames[0], t, o.pan_x, o.pan_y).rms;
  }
  // Five frames of independent primal noise tied by exact motion: the joint
  // solve averages them (measured 0.47x L2, 0.60x L1, 0.58x weighted; uniform
  // control variates, a Jacobi iteration at α = 1, 0.73x).
  const double bound = GetParam() == ReconMethod::kUniform ? 0.85 : 0.7;
  EXPECT_LT(joint_rms, bound * alone_rms) << "joint " << joint_rms / o.frames << " alone " << alone_rms / o.frames;
}

INSTANTIATE_TEST_SUITE_P(Recon, TemporalTargetsSolveTest,
                         ::testing::Values(ReconMethod::kL2, ReconMethod::kL1, ReconMethod::kUniform,
                                           ReconMethod::kWeighted),
                         [](const auto& info) { return std::string(recon_method_name(info.param)); });

// Tiles crop the targets with the buffers; a target outside a tile drops its
// constraints there, and the halo keeps the seams invisible.
TEST(TemporalTargetsTest, TiledSolveMatchesTheWholeWindow) {
  test::SceneOptions o;
  o.frames = 4;
  o.temporal = true;
  o.width = 64;
  o.height = 48;
  o.pan_x = 1;
  o.pan_y = 1;
  o.follow_motion = true;
  o.primal_sigma = 0.05f;
  o.gradient_sigma = 0.01f;
  const GradientWindow w = test::make_window(o);
  ReconSettings s;
  s.method = ReconMethod::kL2;
  s.l2_tolerance = 1e-7;
  s.l2_max_iterations = 2000;
  auto whole = reconstruct(w, s);
  ASSERT_TRUE(whole.ok());
  ReconSettings tiled = s;
  tiled.tile_size = 24;
  auto by_tiles = reconstruct_tiled(w, tiled);
  ASSERT_TRUE(by_tiles.ok()) << by_tiles.status().to_string();
  double worst = 0;
  for (int t = 0; t < o.frames; ++t)
    for (size_t i = 0; i < whole->frames[size_t(t)].data().size(); ++i)
      worst = std::max(worst, double(std::fabs(whole->frames[size_t(t)].data()[i] - by_tiles->frames[size_t(t)].data()[i])));
  EXPECT_LT(worst, 5e-3);
}

}  // namespace
}  // namespace gdvr
