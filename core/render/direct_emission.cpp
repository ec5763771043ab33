#include "core/render/direct_emission.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/math/rng.h"
#include "core/render/tile_scheduler.h"

namespace gdvr {
namespace {

// Keeps the direct pass's random numbers apart from the path samples of the
// same (seed, stream, pixel): those use sample indices 0, 1, 2, ...
constexpr uint32_t kDirectSampleBase = 0x80000000u;

// The probes that find edges: a grid at half-pixel spacing, (2W+1)×(2H+1)
// points, ~4 rays per pixel; pixel (x, y) owns the 3×3 probes from (2x, 2y).
// They only choose how many strata a pixel gets; an emitter smaller than the
// probe spacing can slip between them, and its pixel is then sampled with
// fewer strata (still unbiased).
class ProbeGrid {
 public:
  ProbeGrid(int width, int height) : nx_(2 * width + 1), ny_(2 * height + 1), luminance_(size_t(nx_) * ny_) {}
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  float& at(int i, int j) { return luminance_[size_t(j) * nx_ + i]; }
  float at(int i, int j) const { return luminance_[size_t(j) * nx_ + i]; }

  // How much the emission seen through the pixel varies, from its 3×3 probes:
  // kUniform where all nine agree exactly (no emitter, or inside one of
  // constant radiance: one sample is as good as k²), kEdge where they disagree
  // by more than half of their mean (+ a small floor: an emitter's silhouette,
  // 0 against L, always does), kSmooth otherwise (e.g. the texture of an
  // environment map).
  enum class Variation { kUniform, kSmooth, kEdge };
  Variation variation(int x, int y) const {
    float lo = at(2 * x, 2 * y), hi = lo, sum = 0;
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) {
        const float v = at(2 * x + i, 2 * y + j);
        lo = std::min(lo, v);
        hi = std::max(hi, v);
        sum += v;
      }
    if (hi == lo) return Variation::kUniform;
    return hi - lo > 0.5f * (sum / 9.0f) + 1e-4f ? Variation::kEdge : Variation::kSmooth;
  }

 private:
  int nx_, ny_;
  std::vector<float> luminance_;
};

// What a pixel's camera rays can hit that emits, from the area emitters'
// projected bounds (grown by a pixel for rounding); it decides how the pixel
// is probed.
enum class Reach : uint8_t {
  kNothing,      // no area emitter and no environment: 0 exactly, no ray
  kEnvironment,  // only the environment: its four corner probes first, all nine where they differ
  kEmitter,      // inside an area emitter's bounds: all nine probes
};

std::vector<Reach> emitter_reach(const FrameScene& scene, const PerspectiveCamera& camera, int width, int height,
                                 bool use_bounds) {
  const size_t n = size_t(width) * size_t(height);
  if (!use_bounds) return std::vector<Reach>(n, Reach::kEmitter);
  std::vector<Reach> reach(n, scene.has_environment() ? Reach::kEnvironment : Reach::kNothing);
  for (const Bounds3f& b : scene.area_emitter_bounds()) {
    Vec2f lo, hi;
    if (!camera.project_bounds(b, &lo, &hi)) return std::vector<Reach>(n, Reach::kEmitter);  // unbounded image
    const int x0 = int(std::max(0.0f, std::floor(lo.x) - 1.0f)), y0 = int(std::max(0.0f, std::floor(lo.y) - 1.0f));
    const int x1 = int(std::min(float(width - 1), std::ceil(hi.x) + 1.0f));
    const int y1 = int(std::min(float(height - 1), std::ceil(hi.y) + 1.0f));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) reach[size_t(y) * size_t(width) + size_t(x)] = Reach::kEmitter;
  }
  return reach;
}

}  // namespace

Status DirectEmissionSettings::validate() const {
  if (strata < 0 || edge_strata > 64 || (strata > 0 && edge_strata < strata))
    return invalid_argument("direct light: need 0 <= strata <= edge_strata <= 64 (got strata " +
                            std::to_string(strata) + ", edge_strata " + std::to_string(edge_strata) + ")");
  return Status::Ok();
}

Rgb first_hit_emission(const FrameScene& scene, const Ray& camera_ray) {
  // Most camera rays hit a surface that does not emit: the shading data
  // (normal interpolation, frame) is computed only for emitters.
  RayHit hit;
  if (!scene.intersect_hit(camera_ray, &hit)) return scene.eval_environment(camera_ray.d);
  if (scene.emitter_of_shape(hit.id) < 0) return Rgb(0.0f);
  SurfaceInteraction si;
  scene.interaction(camera_ray, hit, &si);
  return scene.eval_area_emitter(si);
}

Expected<DirectEmissionResult> render_direct_emission(const FrameScene& scene, const PerspectiveCamera& camera,
                                                      int width, int height, const DirectEmissionSettings& settings,
                                                      uint64_t seed, uint32_t stream, const PathTracerSettings& path,
                                                      int threads, const std::atomic<bool>* cancel) {
  if (width <= 0 || height <= 0) return invalid_argument("direct emission: resolution must be positive");
  GDVR_RETURN_IF_ERROR(settings.validate());
  if (!settings.enabled()) return invalid_argument("direct emission: strata must be at least 1");
  DirectEmissionResult out;
  out.direct = Image(width, height, 3);
  if (path.hide_emitters) return out;
  std::atomic<uint64_t> rays{0}, invalid{0}, edges{0}, culled{0};
  TileRunOptions opts;
  opts.threads = threads;
  opts.cancel = cancel;

  // ---- Probes (deterministic positions: the choice of the stratum count
  // depends on no random number of the estimate, so it stays unbiased). Only
  // where emission can be seen (emitter_reach); where only the environment
  // can, the pixel's corner probes come first and its other five only where
  // the corners differ (an environment seen through a gap narrower than a
  // pixel can then slip between them: the pixel is left with fewer strata,
  // still unbiased) ----
  auto pixel = [&](int x, int y) { return size_t(y) * size_t(width) + size_t(x); };
  const std::vector<Reach> reach = emitter_reach(scene, camera, width, height, settings.use_emitter_bounds);
  auto reach_at = [&](int x, int y) { return reach[pixel(x, y)]; };
  const bool adaptive = settings.edge_strata > settings.strata;
  ProbeGrid probes(adaptive ? width : 0, adaptive ? height : 0);
  std::vector<uint8_t> probed(size_t(probes.nx()) * size_t(probes.ny()), 0);
  std::vector<uint8_t> refine(size_t(width) * size_t(height), 0);  // kEnvironment pixels whose corners differ
  // Whether `want` holds for a pixel that owns probe (i, j): pixel (x, y) owns
  // the probes 2x..2x+2 by 2y..2y+2.
  auto any_owner = [&](int i, int j, auto&& want) {
    for (int y = std::max(0, (j - 1) / 2); y <= std::min(height - 1, j / 2); ++y)
      for (int x = std::max(0, (i - 1) / 2); x <= std::min(width - 1, i / 2); ++x)
        if (2 * x <= i && i <= 2 * x + 2 && 2 * y <= j && j <= 2 * y + 2 && want(x, y)) return true;
    return false;
  };
  auto run_probes = [&](auto&& needed) {
    return run_tiles(probes.nx(), probes.ny(), opts, [&](const Tile& tile) {
      uint64_t tile_rays = 0;
      for (int j = tile.y0; j < tile.y1; ++j)
        for (int i = tile.x0; i < tile.x1; ++i) {
          uint8_t& done = probed[size_t(j) * size_t(probes.nx()) + size_t(i)];
          if (done || !needed(i, j)) continue;
          const Rgb e = first_hit_emission(scene, camera.generate_ray({0.5f * float(i), 0.5f * float(j)}));
          probes.at(i, j) = is_finite(e) ? luminance(e) : 0.0f;
          done = 1;
          ++tile_rays;
        }
      rays += tile_rays;
    });
  };
  if (adaptive) {
    Status st = run_probes([&](int i, int j) {
      const bool corner = i % 2 == 0 && j % 2 == 0;
      return any_owner(i, j, [&](int x, int y) {
        const Reach r = reach_at(x, y);
        return r == Reach::kEmitter || (r == Reach::kEnvironment && corner);
      });
    });
    if (!st.ok()) return st;
    bool any_refine = false;
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        if (reach_at(x, y) != Reach::kEnvironment) continue;
        const float c = probes.at(2 * x, 2 * y);
        const bool differ = probes.at(2 * x + 2, 2 * y) != c || probes.at(2 * x, 2 * y + 2) != c ||
                            probes.at(2 * x + 2, 2 * y + 2) != c;
        refine[pixel(x, y)] = differ;
        any_refine = any_refine || differ;
      }
    if (any_refine) {
      st = run_probes([&](int i, int j) {
        return any_owner(i, j, [&](int x, int y) { return refine[pixel(x, y)] != 0; });
      });
      if (!st.ok()) return st;
    }
  }

  if (adaptive && settings.uniform_from_paths) out.from_paths.assign(size_t(width) * size_t(height), 0);

  // ---- Stratified estimate per pixel ----
  Status st = run_tiles(width, height, opts, [&](const Tile& tile) {
    uint64_t tile_rays = 0, tile_invalid = 0, tile_edges = 0, tile_culled = 0;
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        const Reach r = reach_at(x, y);
        if (r == Reach::kNothing) {
          ++tile_culled;  // out.direct is already 0 there
          continue;
        }
        const bool corners_agree = r == Reach::kEnvironment && !refine[pixel(x, y)];
        const ProbeGrid::Variation var = !adaptive       ? ProbeGrid::Variation::kSmooth
                                         : corners_agree ? ProbeGrid::Variation::kUniform
                                                         : probes.variation(x, y);
        if (var == ProbeGrid::Variation::kUniform && settings.uniform_from_paths) {
          out.from_paths[pixel(x, y)] = 1;
          continue;
        }
        const int k = var == ProbeGrid::Variation::kEdge      ? settings.edge_strata
                      : var == ProbeGrid::Variation::kUniform ? 1
                                                              : settings.strata;
        tile_edges += var == ProbeGrid::Variation::kEdge ? 1 : 0;
        const float inv_k = 1.0f / float(k);
        // One stream per pixel; the k² jitters are its first 2k² numbers.
        Sampler sampler(seed, stream, uint32_t(x), uint32_t(y), kDirectSampleBase);
        double sum[3] = {0, 0, 0};
        for (int j = 0; j < k; ++j)
          for (int i = 0; i < k; ++i) {
            const Vec2f u = sampler.next_2d();
            const Ray ray =
                camera.generate_ray({float(x) + (float(i) + u.x) * inv_k, float(y) + (float(j) + u.y) * inv_k});
            const Rgb e = first_hit_emission(scene, ray);
            ++tile_rays;
            if (!is_finite(e)) {
              ++tile_invalid;
              continue;
            }
            for (int c = 0; c < 3; ++c) sum[c] += double(e[c]);
          }
        const double inv_n = 1.0 / double(k * k);
        for (int c = 0; c < 3; ++c) out.direct.at(x, y, c) = float(sum[c] * inv_n);
      }
    rays += tile_rays;
    invalid += tile_invalid;
    edges += tile_edges;
    culled += tile_culled;
  });
  if (!st.ok()) return st;
  out.rays = rays;
  out.invalid_samples = invalid;
  out.edge_pixels = edges;
  out.culled_pixels = culled;
  if (std::find(out.from_paths.begin(), out.from_paths.end(), uint8_t(1)) == out.from_paths.end())
    out.from_paths.clear();
  return out;
}

Image merge_direct_estimates(DirectEmissionResult&& pass, const Image& paths, const Image* paths_b) {
  Image direct = std::move(pass.direct);
  if (pass.from_paths.empty()) return direct;
  const int w = direct.width(), h = direct.height();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (pass.from_paths[size_t(y) * size_t(w) + size_t(x)])
        direct.set_rgb(x, y, paths_b ? (paths.rgb(x, y) + paths_b->rgb(x, y)) * 0.5f : paths.rgb(x, y));
  return direct;
}

}  // namespace gdvr
