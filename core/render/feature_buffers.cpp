#include "core/render/feature_buffers.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/bsdf/bsdf_albedo.h"
#include "core/math/rng.h"
#include "core/render/perspective_camera.h"
#include "core/render/tile_scheduler.h"

namespace gdvr {
namespace {

// The jitter's stream: fixed for every frame (no flicker of static content)
// and apart from the paths' (frame numbers) and the direct-light pass's
// (stream 0, sample indices from 2^31).
constexpr uint32_t kFeatureStream = 0xfeaf0000u;

// The largest float below 1: bsdf_sample's lobe selection by u_lobe <= P
// picks the first lobe at 0 and the last one here, so two calls find both
// branches of a delta surface.
constexpr float kLastLobe = 0x1.fffffep-1f;

Rgb clamp01(Rgb c) {
  auto unit = [](float v) { return v > 0.0f ? std::min(v, 1.0f) : 0.0f; };
  return {unit(c.r), unit(c.g), unit(c.b)};
}

// A delta lobe's tint without the radiance scaling of refraction (weight is
// f / pdf with eta_ti^2 for a transmission; bs.eta = eta_it undoes it): the
// albedo behind clear glass is the albedo, not the radiance it would carry.
Rgb delta_tint(const BsdfSample& bs) { return bs.weight * sqr(bs.eta); }

}  // namespace

Status FeatureBufferSettings::validate() const {
  if (strata < 1 || strata > 64 || max_specular_depth < 0 || max_branches < 1)
    return invalid_argument("feature buffers: need 1 <= strata <= 64, max_specular_depth >= 0 and max_branches >= 1");
  return Status::Ok();
}

FeatureBufferSettings feature_buffer_settings_for(int spp) {
  FeatureBufferSettings s;
  s.strata = std::clamp(int(std::sqrt(double(std::max(spp, 0)))), 2, 4);
  return s;
}

FeatureTracer::FeatureTracer(const FrameScene& scene, const FeatureBufferSettings& settings, bool hide_emitters)
    : scene_(scene), settings_(settings), hide_emitters_(hide_emitters) {
  // Never more waiting than branches made: a split replaces one by two.
  waiting_.reserve(size_t(settings.max_branches));
}

FeatureSample FeatureTracer::trace(const Ray& camera_ray) {
  FeatureSample out;
  const Scene& desc = scene_.scene();
  waiting_.clear();
  waiting_.push_back({camera_ray, Rgb(1.0f), 1.0f, 0});
  int branches = 1;
  bool camera_vertex = true;
  while (!waiting_.empty()) {
    const Branch b = waiting_.back();
    waiting_.pop_back();
    const bool seen_directly = camera_vertex;
    camera_vertex = false;
    ++out.rays;
    RayHit hit;
    // Camera rays pass through hidden emitters (FrameScene::camera_geometry).
    if (!scene_.intersect_hit(b.ray, &hit, seen_directly ? scene_.camera_geometry() : GeometrySet::kAll)) {
      if (!(seen_directly && hide_emitters_)) out.albedo += b.tint * clamp01(scene_.eval_environment(b.ray.d));
      continue;
    }
    SurfaceInteraction si;
    scene_.interaction(b.ray, hit, &si);
    if (seen_directly) out.depth = si.t;
    const Vec3f n = si.sh_frame.n;
    if (scene_.emitter_of_shape(si.shape) >= 0 && !(seen_directly && hide_emitters_)) {
      out.albedo += b.tint * clamp01(scene_.eval_area_emitter(si));
      out.normal += n * b.weight;
      continue;
    }
    const Bsdf& bsdf = desc.bsdfs[size_t(desc.shapes[size_t(si.shape)].bsdf)];
    if (!bsdf.is_delta_only() || b.depth >= settings_.max_specular_depth) {
      out.albedo += b.tint * bsdf_albedo(bsdf, si.uv);
      out.normal += n * b.weight;
      continue;
    }
    BsdfSample first, last;
    const bool has_first = bsdf_sample(bsdf, si.uv, si.wi, 0.0f, {0.5f, 0.5f}, &first);
    const bool has_last = bsdf_sample(bsdf, si.uv, si.wi, kLastLobe, {0.5f, 0.5f}, &last);
    if (!has_first && !has_last) {
      // Nothing leaves (a conductor seen from behind): a black surface.
      out.normal += n * b.weight;
      continue;
    }
    auto follow = [&](const BsdfSample& bs, float probability) {
      waiting_.push_back({si.spawn_ray(si.sh_frame.to_world(bs.wi)), b.tint * delta_tint(bs) * probability,
                          b.weight * probability, b.depth + 1});
    };
    const bool two_lobes = has_first && has_last && first.lobe != last.lobe;
    if (two_lobes && branches < settings_.max_branches) {
      ++branches;
      follow(first, first.pdf);
      follow(last, last.pdf);
    } else if (two_lobes) {
      follow(first.pdf >= last.pdf ? first : last, 1.0f);
    } else {
      follow(has_first ? first : last, 1.0f);
    }
  }
  return out;
}

Expected<FeatureBuffers> render_feature_buffers(const FrameScene& scene, const FrameRenderSettings& frame,
                                                const FeatureBufferSettings& settings,
                                                const std::atomic<bool>* cancel) {
  const int w = frame.width, h = frame.height;
  if (w <= 0 || h <= 0) return invalid_argument("feature buffers: resolution must be positive");
  GDVR_RETURN_IF_ERROR(settings.validate());
  const auto start = std::chrono::steady_clock::now();
  const PerspectiveCamera camera(scene.scene().camera, w, h);
  FeatureBuffers out;
  out.albedo = Image(w, h, 3);
  out.normal = Image(w, h, 3);
  out.depth = Image(w, h, 1);
  std::atomic<uint64_t> rays{0};
  TileRunOptions opts;
  opts.threads = frame.threads;
  opts.tile_size = frame.tile_size;
  opts.cancel = cancel;
  const int k = settings.strata;
  const float inv_k = 1.0f / float(k);
  const float inv_n = 1.0f / float(k * k);
  Status st = run_tiles(w, h, opts, [&](const Tile& tile) {
    FeatureTracer tracer(scene, settings, frame.path.hide_emitters);
    uint64_t tile_rays = 0;
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        // One stream per pixel; the k² jitters are its first 2k² numbers.
        Sampler sampler(frame.seed, kFeatureStream, uint32_t(x), uint32_t(y), 0);
        Rgb albedo;
        Vec3f normal;
        float depth = kMissDepth;
        for (int j = 0; j < k; ++j)
          for (int i = 0; i < k; ++i) {
            const Vec2f u = sampler.next_2d();
            const Ray ray =
                camera.generate_ray({float(x) + (float(i) + u.x) * inv_k, float(y) + (float(j) + u.y) * inv_k});
            const FeatureSample s = tracer.trace(ray);
            albedo += s.albedo;
            normal += s.normal;
            depth = std::min(depth, s.depth);
            tile_rays += s.rays;
          }
        out.albedo.set_rgb(x, y, albedo * inv_n);
        const Vec3f mean_normal = normal * inv_n;
        for (int c = 0; c < 3; ++c) out.normal.at(x, y, c) = mean_normal[c];
        out.depth.at(x, y, 0) = depth;
      }
    rays += tile_rays;
  });
  if (!st.ok()) return st;
  out.rays = rays;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

const std::vector<std::string>& feature_layer_names() {
  static const std::vector<std::string> names = {kAlbedoLayer, kNormalLayer, kDepthLayer};
  return names;
}

void add_feature_layers(FeatureBuffers&& buffers, LayeredImage* out) {
  out->add(kAlbedoLayer, {"R", "G", "B"}, std::move(buffers.albedo));
  out->add(kNormalLayer, {"X", "Y", "Z"}, std::move(buffers.normal));
  out->add(kDepthLayer, {"Z"}, std::move(buffers.depth));
}

void copy_feature_layers(const LayeredImage& from, LayeredImage* to) {
  for (const std::string& name : feature_layer_names())
    if (const ImageLayer* l = from.find(name)) to->layers.push_back(*l);
}

}  // namespace gdvr
