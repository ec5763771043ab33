// Benchmark of the reconstruction solvers (docs/reconstruction.md): L2 and L1
// on one 1280x720 frame and on a 20-frame window with temporal terms,
// amortised per output frame of the 50 %-overlap sliding window.
//
//   gdvr-bench-recon [--threads N] [--runs R] [--width W] [--height H]
//                    [--frames F] [--methods l2,l1] [--no-window] [--no-single]
//                    [--l2-tolerance T] [--l1-inner N] [--l1-outer N] [--l1-inner-tolerance T]
#include <sys/resource.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/recon/reconstruct.h"
#include "core/temporal/tgpt_settings.h"
#include "core/util/cli_args.h"
#include "core/util/memory_tuning.h"

namespace {

using namespace gdvr;

struct Args {
  int threads = 0, runs = 3, width = 1280, height = 720, frames = 20;
  std::vector<ReconMethod> methods = {ReconMethod::kL2, ReconMethod::kL1};
  bool single = true, window = true;
  ReconSettings settings;
};

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux reports KiB
}

// A smooth field with moving edges plus white noise of typical G-PT magnitude
// (primal σ = 0.1, gradients σ = 0.03): a realistic workload for CG/IRLS.
float value(int x, int y, int t, int c) {
  const float s = 0.5f + 0.3f * std::sin(0.013f * x + 0.1f * t + c) * std::cos(0.017f * y);
  const float edge = ((x / 160 + y / 90) % 2 == 0 && x + t * 4 > 300) ? 0.7f : 0.0f;
  return s + edge;
}

std::shared_ptr<const GradientFrame> make_frame(int W, int H, int t, bool temporal) {
  auto f = std::make_shared<GradientFrame>();
  for (Term term : kAllTerms) {
    if (is_temporal(term) && !temporal) continue;
    f->buffer(term) = Image(W, H, 3);
  }
  tbb::parallel_for(0, H, [&](int y) {
    std::mt19937 rng(unsigned(t * 100003 + y));
    std::normal_distribution<float> n(0.0f, 1.0f);
    for (int x = 0; x < W; ++x)
      for (int c = 0; c < 3; ++c) {
        const int xr = std::min(x + 1, W - 1), yd = std::min(y + 1, H - 1);
        const float v = value(x, y, t, c), vn = value(x, y, t + 1, c);
        const float dx = value(xr, y, t, c) - v, dy = value(x, yd, t, c) - v;
        const float dxn = value(xr, y, t + 1, c) - vn, dyn = value(x, yd, t + 1, c) - vn;
        f->buffer(Term::kPrimal).at(x, y, c) = v + 0.1f * n(rng);
        f->buffer(Term::kDx).at(x, y, c) = dx + 0.03f * n(rng);
        f->buffer(Term::kDy).at(x, y, c) = dy + 0.03f * n(rng);
        if (temporal) {
          f->buffer(Term::kDt).at(x, y, c) = vn - v + 0.03f * n(rng);
          f->buffer(Term::kDxdt).at(x, y, c) = dxn - dx + 0.03f * n(rng);
          f->buffer(Term::kDydt).at(x, y, c) = dyn - dy + 0.03f * n(rng);
        }
      }
  });
  return f;
}

double rms_error(const Image& img, int t) {
  double e = 0;
  for (int y = 0; y < img.height(); ++y)
    for (int x = 0; x < img.width(); ++x)
      for (int c = 0; c < 3; ++c) e += std::pow(img.at(x, y, c) - value(x, y, t, c), 2);
  return std::sqrt(e / (img.pixel_count() * 3.0));
}

void bench(const char* label, const GradientWindow& w, ReconSettings s, ReconMethod m, int runs,
           int frames_per_output) {
  s.method = m;
  std::vector<double> times;
  ReconStats stats;
  double err = 0;
  for (int r = 0; r < runs; ++r) {
    auto res = reconstruct(w, s);
    if (!res.ok()) {
      std::fprintf(stderr, "%s\n", res.status().to_string().c_str());
      std::exit(1);
    }
    times.push_back(res->stats.seconds);
    stats = res->stats;
    err = rms_error(res->frames[w.size() / 2], w.size() / 2);
  }
  std::sort(times.begin(), times.end());
  const double median = times[times.size() / 2];
  std::printf("%-22s %-3s median %8.3f s  (min %.3f, max %.3f, %d runs)  per output frame %7.3f s  "
              "cg_iterations %d  rel_residual %.2e  rms_err(centre) %.4f (primal %.4f)  peak_rss %.0f MiB\n",
              label, recon_method_name(m), median, times.front(), times.back(), runs, median / frames_per_output,
              stats.cg_iterations, stats.relative_residual, err,
              rms_error(w.frames[w.size() / 2]->buffer(Term::kPrimal), w.size() / 2), peak_rss_mib());
  std::fflush(stdout);
}

// The hop of T-GPT's sliding window of `frames` frames (core/temporal/temporal_window.h).
int window_hop(int frames) {
  TgptSettings s;
  s.window = frames;
  return s.effective_hop();
}

}  // namespace

int main(int argc, char** argv) {
  gdvr::retain_freed_memory_for_reuse();  // core/util/memory_tuning.h: batch tool
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    const auto next = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "missing value for %s\n", k.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (k == "--threads") a.threads = int(tools::int_option("gdvr-bench-recon", k, next(), 0, 1024));
    else if (k == "--runs") a.runs = int(tools::int_option("gdvr-bench-recon", k, next(), 1, 1000));
    else if (k == "--width") a.width = int(tools::int_option("gdvr-bench-recon", k, next(), 1, 16384));
    else if (k == "--height") a.height = int(tools::int_option("gdvr-bench-recon", k, next(), 1, 16384));
    else if (k == "--frames") a.frames = int(tools::int_option("gdvr-bench-recon", k, next(), 1, 100000));
    else if (k == "--no-window") a.window = false;
    else if (k == "--l2-tolerance") a.settings.l2_tolerance = tools::number_option("gdvr-bench-recon", k, next(), 0, 1);
    else if (k == "--l1-inner-tolerance") a.settings.l1_inner_tolerance = tools::number_option("gdvr-bench-recon", k, next(), 0, 1);
    else if (k == "--l1-inner") a.settings.l1_inner_iterations = int(tools::int_option("gdvr-bench-recon", k, next(), 1, 100000));
    else if (k == "--l1-outer") a.settings.l1_outer_iterations = int(tools::int_option("gdvr-bench-recon", k, next(), 1, 100000));
    else if (k == "--no-single") a.single = false;
    else if (k == "--methods") {
      a.methods.clear();
      std::stringstream ss(next());
      std::string m;
      while (std::getline(ss, m, ',')) {
        auto p = parse_recon_method(m);
        if (!p.ok()) {
          std::fprintf(stderr, "%s\n", p.status().to_string().c_str());
          return 2;
        }
        a.methods.push_back(p.value());
      }
    } else {
      std::fprintf(stderr, "unknown option %s\n", k.c_str());
      return 2;
    }
  }
  const int threads = a.threads > 0 ? a.threads : int(tbb::info::default_concurrency());
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, size_t(threads));
  if (Status st = a.settings.validate(); !st.ok()) {
    std::fprintf(stderr, "%s\n", st.to_string().c_str());
    return 2;
  }
  std::printf("gdvr-bench-recon: %dx%d, threads %d, runs %d, window %d frames (hop %d)\n", a.width, a.height, threads,
              a.runs, a.frames, window_hop(a.frames));

  if (a.single) {
    GradientWindow w;
    w.frames.push_back(make_frame(a.width, a.height, 0, false));
    for (ReconMethod m : a.methods) bench("single frame", w, a.settings, m, a.runs, 1);
  }
  if (a.window) {
    GradientWindow w;
    for (int t = 0; t < a.frames; ++t) w.frames.push_back(make_frame(a.width, a.height, t, true));
    // The sliding window advances by its hop: each solve pays for hop frames.
    const int hop = window_hop(a.frames);
    char label[64];
    std::snprintf(label, sizeof label, "window %d (hop %d)", a.frames, hop);
    for (ReconMethod m : a.methods) bench(label, w, a.settings, m, a.runs, hop);
  }
  return 0;
}
