// Benchmark of G-PT against PT (docs/gpt.md):
// - cost: G-PT wall time per spp / PT's at equal spp, per scene, shift mapping
//   and cached-path RR setting, median over runs, PT measured in the same run;
// - quality: relMSE (per-pixel and global, docs/report.md) at equal wall-time
//   budgets of PT and G-PT with L1, L2 and weighted reconstruction against the
//   Mitsuba references, plus the improvement predicted from measured variances
//   (docs/reconstruction.md, "Predicted improvement") next to the achieved one at equal spp.
//
//   gdvr-bench-gpt [--scenes cbox,veach-mis,matpreview] [--runs 3] [--spp 8]
//                  [--budgets 2,4,8] [--threads 2] [--no-cost] [--no-quality] [--default-only]
//                  [--quality-shift reconnect] [--own-sub-pixel-positions] [--seed N]
//                  [--pair-primal]
//                  [--source-dir DIR]
// Run from the repository root (or set GDVR_SOURCE_DIR / --source-dir).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "core/gradient/gpt_integrator.h"
#include "core/io/image_io.h"
#include "core/recon/predicted_improvement.h"
#include "core/recon/reconstruct.h"
#include "core/scene/mitsuba_loader.h"
#include "core/util/cli_args.h"
#include "core/util/memory_tuning.h"

namespace {

using namespace gdvr;

struct BenchScene {
  std::string name, xml, reference;
  std::map<std::string, std::string> params;
};

const std::vector<BenchScene> kScenes = {
    {"cbox", "scenes/cbox/cbox-rgb.xml", "scenes/references/cbox_256_box_4096spp.exr", {{"res", "256"}}},
    {"veach-mis", "scenes/veach-mis/scene.xml", "scenes/references/veach-mis_320x180_box_4096spp.exr",
     {{"resx", "320"}, {"resy", "180"}}},
    {"matpreview", "scenes/matpreview/matpreview.xml", "scenes/references/matpreview_256x192_box_4096spp.exr",
     {{"width", "256"}, {"height", "192"}}},
};

struct Args {
  std::vector<std::string> scenes = {"cbox", "veach-mis", "matpreview"};
  int runs = 3, spp = 8, threads = 2;
  std::vector<double> budgets = {2, 4, 8};
  bool cost = true, quality = true;
  bool default_only = false;  // cost of the default configuration only (reconnect, cached RR on)
  ShiftMapping quality_shift = ShiftMapping::kReconnect;
  bool own_positions = false;  // quality with GptSettings::shared_jitter off
  bool pair_primal = false;    // quality: also the same samples with GptSettings::pair_primal
  uint64_t quality_seed = 1234;
  std::string source_dir = std::getenv("GDVR_SOURCE_DIR") ? std::getenv("GDVR_SOURCE_DIR") : ".";
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) out.push_back(item);
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

double rel_mse_per_pixel(const Image& img, const Image& ref) {
  double sum = 0;
  for (size_t k = 0; k < ref.data().size(); ++k) {
    double r = ref.data()[k], d = double(img.data()[k]) - r;
    sum += d * d / (r * r + 0.01);
  }
  return sum / double(ref.data().size());
}

double rel_mse_global(const Image& img, const Image& ref) {
  double num = 0, den = 0;
  for (size_t k = 0; k < ref.data().size(); ++k) {
    double r = ref.data()[k], d = double(img.data()[k]) - r;
    num += d * d;
    den += r * r;
  }
  return den > 0 ? num / den : 0;
}

double mean_finite(const Image& img) {
  double s = 0;
  size_t n = 0;
  for (float v : img.data())
    if (std::isfinite(v)) s += v, ++n;
  return n ? s / double(n) : 0;
}

struct Loaded {
  Scene desc;
  std::unique_ptr<FrameScene> scene;
  FrameRenderSettings render;
  Image reference;
};

Expected<Loaded> load(const Args& a, const BenchScene& bs) {
  LoadOptions opts;
  opts.params = bs.params;
  auto desc = load_mitsuba_scene(a.source_dir + "/" + bs.xml, opts);
  if (!desc.ok()) return desc.status();
  Loaded l;
  l.desc = std::move(desc.value());
  auto fs = FrameScene::create(l.desc, {});
  if (!fs.ok()) return fs.status();
  l.scene = std::move(fs.value());
  auto ref = read_rgb_image(a.source_dir + "/" + bs.reference);
  if (!ref.ok()) return ref.status();
  l.reference = std::move(ref.value());
  l.render.width = l.desc.defaults.width;
  l.render.height = l.desc.defaults.height;
  l.render.path.max_depth = l.desc.defaults.max_depth;
  l.render.path.rr_depth = l.desc.defaults.rr_depth;
  l.render.path.hide_emitters = l.desc.defaults.hide_emitters;
  l.render.threads = a.threads;
  return l;
}

Image reconstruct_final(const GptFrameResult& r, ReconMethod method, double* seconds) {
  GradientFrame gf;
  gf.buffer(Term::kPrimal) = r.buffers.primal;
  gf.buffer(Term::kDx) = r.buffers.dx;
  gf.buffer(Term::kDy) = r.buffers.dy;
  gf.variance(Term::kPrimal) = r.buffers.primal_var;
  gf.variance(Term::kDx) = r.buffers.dx_var;
  gf.variance(Term::kDy) = r.buffers.dy_var;
  ReconSettings rs;
  rs.method = method;
  auto rec = reconstruct_frame(gf, rs);
  if (!rec.ok()) {
    std::fprintf(stderr, "reconstruction failed: %s\n", rec.status().to_string().c_str());
    std::exit(1);
  }
  *seconds = rec->stats.seconds;
  Image img = rec->frames.front();
  for (size_t k = 0; k < img.data().size(); ++k) img.data()[k] += r.buffers.direct.data()[k];
  return img;
}

// G-PT as a job runs it: with the stratified direct-light pass (PT keeps its
// own samples, as a pt job does).
FrameRenderSettings with_direct_pass(FrameRenderSettings rs) {
  rs.direct = default_direct_emission(/*gradient_domain=*/true);
  return rs;
}

void run_cost(const Args& a, const BenchScene& bs, Loaded& l) {
  struct Config {
    ShiftMapping shift;
    bool rr;
    bool shared_jitter = true;  // GptSettings::shared_jitter
  };
  const std::vector<Config> all = {{ShiftMapping::kReplay, false},       {ShiftMapping::kReplay, true},
                                   {ShiftMapping::kReconnect, true},     {ShiftMapping::kReconnect, false},
                                   {ShiftMapping::kReconnect, true, false}, {ShiftMapping::kHybrid, true},
                                   {ShiftMapping::kHybrid, false}};
  const std::vector<Config> configs = a.default_only ? std::vector<Config>{all[2]} : all;
  std::vector<std::vector<double>> ratios(configs.size());
  std::vector<double> pt_times, fail_rates(configs.size());
  for (int run = 0; run < a.runs; ++run) {
    FrameRenderSettings rs = l.render;
    rs.spp = a.spp;
    rs.seed = uint64_t(run);
    auto pt = render_frame_pt(*l.scene, rs, 0, {});
    if (!pt.ok()) std::exit(1);
    pt_times.push_back(pt->seconds);
    for (size_t c = 0; c < configs.size(); ++c) {
      GptSettings g = GptSettings::defaults_for(configs[c].shift);
      g.cached_rr = configs[c].rr;
      g.shared_jitter = configs[c].shared_jitter;
      auto r = render_frame_gpt(*l.scene, with_direct_pass(rs), g, 0, {});
      if (!r.ok()) std::exit(1);
      ratios[c].push_back(r->seconds / pt->seconds);
      fail_rates[c] = r->shift_failure_rate;
    }
  }
  std::printf("cost %s %dx%d %d spp: PT %.3f s (median of %d)\n", bs.name.c_str(), l.render.width, l.render.height,
              a.spp, median(pt_times), a.runs);
  for (size_t c = 0; c < configs.size(); ++c)
    std::printf("  gpt %-9s cached_rr=%-3s%s time/PT %.2fx  (failure rate %.3f)\n",
                shift_mapping_name(configs[c].shift), configs[c].rr ? "on" : "off",
                configs[c].shared_jitter ? "" : " own sub-pixel positions", median(ratios[c]), fail_rates[c]);
  std::fflush(stdout);
}

// Primal, L2, L1 and weighted relMSE of one G-PT frame against the reference,
// and L2's predicted against achieved improvement over the primal (§6).
void report_quality(const GptFrameResult& r, const Image& reference, double pt_pp, double pt_gl) {
  Image primal = r.buffers.primal;
  for (size_t k = 0; k < primal.data().size(); ++k) primal.data()[k] += r.buffers.direct.data()[k];
  const double primal_pp = rel_mse_per_pixel(primal, reference);
  std::printf("  primal      relMSE %.5f (global %.5f)\n", primal_pp, rel_mse_global(primal, reference));
  double l2_pp = 0;
  for (ReconMethod m : {ReconMethod::kL2, ReconMethod::kL1, ReconMethod::kWeighted}) {
    double secs = 0;
    Image img = reconstruct_final(r, m, &secs);
    const double pp = rel_mse_per_pixel(img, reference), gl = rel_mse_global(img, reference);
    if (m == ReconMethod::kL2) l2_pp = pp;
    std::printf("  %-9s   relMSE %.5f (global %.5f)  PT/G-PT %.2fx (global %.2fx)  solve %.2f s\n",
                recon_method_name(m), pp, gl, pt_pp / pp, pt_gl / gl, secs);
  }
  // Predicted improvement of L2 over the G-PT primal from the measured variances (§6).
  NoiseLevels noise;
  noise[Term::kPrimal] = mean_finite(r.buffers.primal_var);
  noise[Term::kDx] = mean_finite(r.buffers.dx_var);
  noise[Term::kDy] = mean_finite(r.buffers.dy_var);
  auto predicted = predicted_improvement(noise, ReconSettings(), /* temporal = */ false);
  std::printf("  L2 vs primal at equal spp: predicted %.2fx, achieved %.2fx (relMSE)\n",
              predicted.ok() ? predicted.value() : -1.0, primal_pp / l2_pp);
}

void run_quality(const Args& a, const BenchScene& bs, Loaded& l) {
  for (double budget : a.budgets) {
    FrameRenderSettings rs = l.render;
    rs.spp = 1;
    rs.time_budget_s = budget;
    rs.seed = a.quality_seed;
    auto pt = render_frame_pt(*l.scene, rs, 0, {});
    if (!pt.ok()) std::exit(1);
    const double pt_pp = rel_mse_per_pixel(pt->color, l.reference), pt_gl = rel_mse_global(pt->color, l.reference);
    for (bool rr : {true, false}) {
      GptSettings g = GptSettings::defaults_for(a.quality_shift);
      g.cached_rr = rr;
      g.shared_jitter = !a.own_positions;
      auto r = render_frame_gpt(*l.scene, with_direct_pass(rs), g, 0, {});
      if (!r.ok()) std::exit(1);
      std::printf("quality %s budget %.1f s: PT %d spp relMSE %.5f (global %.5f) | G-PT %s cached_rr=%s %d spp in "
                  "%.2f s, failure %.3f\n",
                  bs.name.c_str(), budget, pt->spp, pt_pp, pt_gl, shift_mapping_name(a.quality_shift),
                  rr ? "on" : "off", r->spp, r->seconds, r->shift_failure_rate);
      report_quality(*r, l.reference, pt_pp, pt_gl);
      if (a.pair_primal) {
        // The same samples (same seed and spp, no budget), with the pair primal.
        GptSettings gp = g;
        gp.pair_primal = true;
        FrameRenderSettings fixed = with_direct_pass(rs);
        fixed.time_budget_s = 0;
        fixed.spp = r->spp;
        auto rp = render_frame_gpt(*l.scene, fixed, gp, 0, {});
        if (!rp.ok()) std::exit(1);
        std::printf("  -- the same %d spp with the pair primal:\n", rp->spp);
        report_quality(*rp, l.reference, pt_pp, pt_gl);
      }
      std::fflush(stdout);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  gdvr::retain_freed_memory_for_reuse();  // core/util/memory_tuning.h: batch tool
  Args a;
  for (int i = 1; i < argc; ++i) {
    std::string s = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", s.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (s == "--scenes") a.scenes = split(next());
    else if (s == "--runs") a.runs = int(tools::int_option("gdvr-bench-gpt", s, next(), 1, 1000));
    else if (s == "--spp") a.spp = int(tools::int_option("gdvr-bench-gpt", s, next(), 1, 1 << 20));
    else if (s == "--threads") a.threads = int(tools::int_option("gdvr-bench-gpt", s, next(), 1, 1024));
    else if (s == "--budgets") {
      a.budgets.clear();
      for (const auto& b : split(next())) a.budgets.push_back(tools::number_option("gdvr-bench-gpt", s, b, 1e-3, 1e6));
    } else if (s == "--no-cost") a.cost = false;
    else if (s == "--no-quality") a.quality = false;
    else if (s == "--default-only") a.default_only = true;
    else if (s == "--own-sub-pixel-positions") a.own_positions = true;
    else if (s == "--pair-primal") a.pair_primal = true;
    else if (s == "--seed") a.quality_seed = uint64_t(tools::int_option("gdvr-bench-gpt", s, next(), 0, 1LL << 62));
    else if (s == "--source-dir") a.source_dir = next();
    else if (s == "--quality-shift") {
      auto m = parse_shift_mapping(next());
      if (!m.ok()) {
        std::fprintf(stderr, "%s\n", m.status().to_string().c_str());
        return 2;
      }
      a.quality_shift = m.value();
    } else {
      std::fprintf(stderr, "unknown argument %s\n", s.c_str());
      return 2;
    }
  }
  for (const BenchScene& bs : kScenes) {
    if (std::find(a.scenes.begin(), a.scenes.end(), bs.name) == a.scenes.end()) continue;
    auto l = load(a, bs);
    if (!l.ok()) {
      std::fprintf(stderr, "%s: %s\n", bs.name.c_str(), l.status().to_string().c_str());
      return 1;
    }
    if (a.cost) run_cost(a, bs, l.value());
    if (a.quality) run_quality(a, bs, l.value());
  }
  return 0;
}
