// Benchmark of the reconstruction solvers (docs/reconstruction.md): L2 and L1
// on one 1280x720 frame and on a 20-frame window with temporal terms,
// amortised per output frame of the 50 %-overlap sliding window.
//
//   gdvr-bench-recon [--threads N] [--runs R] [--width W] [--height H]
//                    [--frames F] [--methods l2,l1] [--no-window] [--no-single]
//                    [--l2-tolerance T] [--l1-inner N] [--l1-outer N] [--l1-inner-tolerance T]
//                    [--alpha A] [--tile-size N] [--tile-halo H] [--diff-png PATH] [--pan P]
//   gdvr-bench-recon --impulse [--alpha A] [--frames F]
// --tile-size N also solves each case by tiles (core/recon/tiled_reconstruct.h)
// and reports the time and the agreement with the whole-frame solve (max
// |difference|, relMSE, the seam metric along tile borders); --diff-png
// writes |tiled − whole| of the centre frame around a tile corner, scaled
// so that the largest difference is white.
// GDVR_POISSON_KERNELS=baseline|avx2|avx512 picks the solve's kernels
// (core/recon/poisson_kernels.h; all give the same bits).
// --pan P makes the window's content move P pixels right per frame, with the
// temporal terms following it (GradientFrame::temporal_target; the
// reconstruction's motion-compensated path, docs/reconstruction.md).
// --impulse prints the L2 operator's impulse response against distance, from
// which the default halo is chosen (docs/reconstruction.md, "Tiled solve").
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

#include "core/image/error_metrics.h"
#include "core/io/image_io.h"
#include "core/recon/impulse_response.h"
#include "core/recon/poisson_kernels.h"
#include "core/recon/reconstruct.h"
#include "core/recon/tile_seams.h"
#include "core/recon/tiled_reconstruct.h"
#include "core/temporal/tgpt_settings.h"
#include "core/util/cli_args.h"
#include "core/util/memory_tuning.h"

namespace {

using namespace gdvr;

struct Args {
  int threads = 0, runs = 3, width = 1280, height = 720, frames = 20;
  std::vector<ReconMethod> methods = {ReconMethod::kL2, ReconMethod::kL1};
  bool single = true, window = true, impulse = false;
  int tile_size = 0;
  std::string diff_png;
  ReconSettings settings;
  bool variances() const {
    return std::find(methods.begin(), methods.end(), ReconMethod::kWeighted) != methods.end();
  }
};

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;  // Linux reports KiB
}

// Pixels per frame the content moves right (--pan).
int g_pan = 0;

// A smooth field with moving edges plus white noise of typical G-PT magnitude
// (primal σ = 0.1, gradients σ = 0.03): a realistic workload for CG/IRLS.
float value(int x, int y, int t, int c) {
  x -= g_pan * t;
  const float s = 0.5f + 0.3f * std::sin(0.013f * x + 0.1f * t + c) * std::cos(0.017f * y);
  const float edge = ((x / 160 + y / 90) % 2 == 0 && x + t * 4 > 300) ? 0.7f : 0.0f;
  return s + edge;
}

// `variances`: the noise's true variances too (the weighted control variates need them).
std::shared_ptr<const GradientFrame> make_frame(int W, int H, int t, bool temporal, bool variances) {
  auto f = std::make_shared<GradientFrame>();
  if (temporal && g_pan != 0) {
    f->temporal_target = Image(W, H, 2);
    for (int i = 0; i < W * H; ++i) f->temporal_target.data()[size_t(i) * 2] = float(g_pan);
  }
  for (Term term : kAllTerms) {
    if (is_temporal(term) && !temporal) continue;
    f->buffer(term) = Image(W, H, 3);
    if (variances) {
      f->variance(term) = Image(W, H, 3);
      for (float& v : f->variance(term).data()) v = term == Term::kPrimal ? 0.01f : 0.0009f;
    }
  }
  tbb::parallel_for(0, H, [&](int y) {
    std::mt19937 rng(unsigned(t * 100003 + y));
    std::normal_distribution<float> n(0.0f, 1.0f);
    for (int x = 0; x < W; ++x)
      for (int c = 0; c < 3; ++c) {
        const int xr = std::min(x + 1, W - 1), yd = std::min(y + 1, H - 1);
        // The next frame at the target (the same pixel unless --pan).
        const int tx = std::clamp(x + g_pan, 0, W - 1), txr = std::min(tx + 1, W - 1);
        const float v = value(x, y, t, c), vn = value(tx, y, t + 1, c);
        const float dx = value(xr, y, t, c) - v, dy = value(x, yd, t, c) - v;
        const float dxn = value(txr, y, t + 1, c) - vn, dyn = value(tx, yd, t + 1, c) - vn;
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

// The tiled solve against the whole-frame one, on the same window.
void compare_tiled(const char* label, const GradientWindow& w, const ReconSettings& s, const ReconResult& whole,
                   int runs, int frames_per_output, const std::string& diff_png) {
  std::vector<double> times;
  ReconResult tiled;
  for (int r = 0; r < runs; ++r) {
    auto res = reconstruct_tiled(w, s);
    if (!res.ok()) {
      std::fprintf(stderr, "%s\n", res.status().to_string().c_str());
      std::exit(1);
    }
    times.push_back(res->stats.seconds);
    tiled = std::move(res.value());
  }
  std::sort(times.begin(), times.end());
  const TileGrid grid = tile_grid_for(s, w.width(), w.height()).value();
  double max_abs = 0;
  RelMseSums sums;
  SeamMetric seam_tiled, seam_whole;
  for (size_t t = 0; t < whole.frames.size(); ++t) {
    for (size_t i = 0; i < whole.frames[t].data().size(); ++i)
      max_abs = std::max(max_abs, double(std::fabs(tiled.frames[t].data()[i] - whole.frames[t].data()[i])));
    sums.add(rel_mse_sums(tiled.frames[t], whole.frames[t]).value());
    const SeamMetric a = tile_seam_metric(tiled.frames[t], grid), b = tile_seam_metric(whole.frames[t], grid);
    seam_tiled.border += a.border / whole.frames.size();
    seam_tiled.elsewhere += a.elsewhere / whole.frames.size();
    seam_whole.border += b.border / whole.frames.size();
    seam_whole.elsewhere += b.elsewhere / whole.frames.size();
  }
  const double median = times[times.size() / 2];
  std::printf("%-22s %-3s tiled (%s) median %8.3f s  per output frame %7.3f s  cg_iterations %d  "
              "vs whole: max|diff| %.2e  relMSE global %.2e per-pixel %.2e  seam border/elsewhere %.4f (whole %.4f), "
              "border tiled/whole %.5f  peak_rss %.0f MiB\n",
              label, recon_method_name(s.method), grid.to_string().c_str(), median, median / frames_per_output,
              tiled.stats.cg_iterations, max_abs, sums.global(), sums.per_pixel(), seam_tiled.ratio(),
              seam_whole.ratio(), seam_tiled.border / seam_whole.border, peak_rss_mib());
  std::fflush(stdout);
  if (!diff_png.empty() && grid.count() > 1) {
    // 256×256 around the corner where the first four tiles meet (or the first border).
    const int cx = grid.tile(std::min(1, grid.count() - 1)).core.x0;
    const int cy = grid.rows() > 1 ? grid.tile(grid.columns()).core.y0 : w.height() / 2;
    const int x0 = std::clamp(cx - 128, 0, std::max(0, w.width() - 256)),
              y0 = std::clamp(cy - 128, 0, std::max(0, w.height() - 256));
    const int t = w.size() / 2;
    Image diff(std::min(256, w.width()), std::min(256, w.height()), 3);
    float largest = 0;
    for (int y = 0; y < diff.height(); ++y)
      for (int x = 0; x < diff.width(); ++x)
        for (int c = 0; c < 3; ++c) {
          diff.at(x, y, c) = std::fabs(tiled.frames[t].at(x0 + x, y0 + y, c) - whole.frames[t].at(x0 + x, y0 + y, c));
          largest = std::max(largest, diff.at(x, y, c));
        }
    // Scaled so that the largest difference is white: a seam would be a line.
    if (largest > 0)
      for (float& v : diff.data()) v /= largest;
    if (Status st = write_png8(diff_png, diff); !st.ok()) std::fprintf(stderr, "%s\n", st.to_string().c_str());
    else std::printf("wrote %s: |tiled - whole| / %.2e, frame %d, pixels [%d,%d)x[%d,%d)\n", diff_png.c_str(), largest, t,
                     x0, x0 + diff.width(), y0, y0 + diff.height());
  }
}

// The operator's impulse response against distance (core/recon/impulse_response.h).
void impulse_response(const Args& a) {
  const int size = 161;
  auto r = impulse_response_by_distance(a.settings, size, a.frames);
  if (!r.ok()) {
    std::fprintf(stderr, "%s\n", r.status().to_string().c_str());
    std::exit(1);
  }
  std::printf("impulse response, alpha %g, %d frames of %dx%d, all six terms (CG to 1e-10): "
              "max |x| at Chebyshev distance r / peak\n",
              a.settings.alpha, a.frames, size, size);
  for (int d = 0; d <= size / 2; d += 4) std::printf("  r = %3d  %.3e\n", d, r.value()[size_t(d)]);
}

void bench(const char* label, const GradientWindow& w, ReconSettings s, ReconMethod m, int runs,
           int frames_per_output, const Args& a) {
  s.method = m;
  std::vector<double> times;
  ReconStats stats;
  double err = 0;
  ReconResult last;
  for (int r = 0; r < runs; ++r) {
    auto res = reconstruct(w, s);
    if (!res.ok()) {
      std::fprintf(stderr, "%s\n", res.status().to_string().c_str());
      std::exit(1);
    }
    times.push_back(res->stats.seconds);
    stats = res->stats;
    err = rms_error(res->frames[w.size() / 2], w.size() / 2);
    last = std::move(res.value());
  }
  std::sort(times.begin(), times.end());
  const double median = times[times.size() / 2];
  std::printf("%-22s %-3s median %8.3f s  (min %.3f, max %.3f, %d runs)  per output frame %7.3f s  "
              "cg_iterations %d  rel_residual %.2e  rms_err(centre) %.4f (primal %.4f)  peak_rss %.0f MiB\n",
              label, recon_method_name(m), median, times.front(), times.back(), runs, median / frames_per_output,
              stats.cg_iterations, stats.relative_residual, err,
              rms_error(w.frames[w.size() / 2]->buffer(Term::kPrimal), w.size() / 2), peak_rss_mib());
  std::fflush(stdout);
  if (a.tile_size > 0) {
    s.tile_size = a.tile_size;
    compare_tiled(label, w, s, last, runs, frames_per_output, a.diff_png);
  }
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
    else if (k == "--impulse") a.impulse = true;
    else if (k == "--alpha") a.settings.alpha = tools::number_option("gdvr-bench-recon", k, next(), 1e-6, 1e6);
    else if (k == "--tile-size") a.tile_size = int(tools::int_option("gdvr-bench-recon", k, next(), 16, 1 << 20));
    else if (k == "--tile-halo") a.settings.tile_halo = int(tools::int_option("gdvr-bench-recon", k, next(), 0, 1 << 20));
    else if (k == "--diff-png") a.diff_png = next();
    else if (k == "--pan") g_pan = int(tools::int_option("gdvr-bench-recon", k, next(), -64, 64));
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
  if (a.impulse) {
    impulse_response(a);
    return 0;
  }
  std::printf("gdvr-bench-recon: %dx%d, threads %d, runs %d, window %d frames (hop %d), %s kernels\n", a.width,
              a.height, threads, a.runs, a.frames, window_hop(a.frames), poisson_kernels().isa);

  if (a.single) {
    GradientWindow w;
    w.frames.push_back(make_frame(a.width, a.height, 0, false, a.variances()));
    for (ReconMethod m : a.methods) bench("single frame", w, a.settings, m, a.runs, 1, a);
  }
  if (a.window) {
    GradientWindow w;
    for (int t = 0; t < a.frames; ++t) w.frames.push_back(make_frame(a.width, a.height, t, true, a.variances()));
    // The sliding window advances by its hop: each solve pays for hop frames.
    const int hop = window_hop(a.frames);
    char label[64];
    std::snprintf(label, sizeof label, "window %d (hop %d)", a.frames, hop);
    for (ReconMethod m : a.methods) bench(label, w, a.settings, m, a.runs, hop, a);
  }
  return 0;
}
