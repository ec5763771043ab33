// Shared pieces of the stiff and extreme suite (issue 6): the case table
// (scenes/stiff/*.xml with their parameters), job construction for every
// integrator and shift, runtime assets (HDR sun environment, pixel-aligned
// checker mesh), PT references (cached), finiteness and relMSE.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/io/image_io.h"
#include "core/job/job_runner.h"
#include "core/render/frame_scene.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr::stiff {

inline std::string stiff_dir() { return std::string(GDVR_SOURCE_DIR) + "/scenes/stiff"; }

// ---- Runtime assets (written once per process into a private temp folder) ----

inline void remove_asset_dir();

// ctest runs every test in a process of its own, so the folder is removed when
// the process exits (registered after `dir` is made, so it runs before `dir`
// is destroyed); otherwise each run of the suite would leave ~100 behind.
inline const std::string& asset_dir() {
  static const std::string dir = [] {
    std::string d = (std::filesystem::temp_directory_path() / ("gdvr_stiff_" + std::to_string(::getpid()))).string();
    std::filesystem::create_directories(d);
    return d;
  }();
  static const bool removed_at_exit = (std::atexit(remove_asset_dir), true);
  (void)removed_at_exit;
  return dir;
}

inline void remove_asset_dir() {
  std::error_code ignored;  // nothing to report at exit; a leftover folder is harmless
  std::filesystem::remove_all(asset_dir(), ignored);
}

// 64 x 32 lat-long sky of luminance ~1 with a 2 x 2 texel sun of 1e5 x the sky.
inline std::string sun_envmap_path() {
  static const std::string path = [] {
    std::string p = asset_dir() + "/sun_sky.exr";
    Image img(64, 32, 3);
    for (int y = 0; y < 32; ++y)
      for (int x = 0; x < 64; ++x) {
        img.at(x, y, 0) = 0.8f, img.at(x, y, 1) = 0.95f, img.at(x, y, 2) = 1.2f;
        if ((y == 8 || y == 9) && (x == 20 || x == 21))
          for (int c = 0; c < 3; ++c) img.at(x, y, c) = 1e5f;
      }
    LayeredImage li;
    li.add("", {"R", "G", "B"}, img);
    Status st = write_exr(p, li);
    EXPECT_TRUE(st.ok()) << st.to_string();
    return p;
  }();
  return path;
}

// Tiles exactly one pixel wide at resolution res x res for checker.xml's
// camera (90 degree fov, plane z = -1 spans [-1, 1]^2), pixels with (i + j) even.
inline std::string checker_mesh_path(int res) {
  std::string p = asset_dir() + "/checker_" + std::to_string(res) + ".obj";
  if (std::filesystem::exists(p)) return p;
  std::ofstream os(p);
  int n = 0;
  for (int j = 0; j < res; ++j)
    for (int i = 0; i < res; ++i) {
      if ((i + j) % 2) continue;
      double x0 = -1.0 + 2.0 * i / res, x1 = -1.0 + 2.0 * (i + 1) / res;
      double y0 = -1.0 + 2.0 * j / res, y1 = -1.0 + 2.0 * (j + 1) / res;
      char buf[256];
      std::snprintf(buf, sizeof(buf), "v %.9g %.9g -1\nv %.9g %.9g -1\nv %.9g %.9g -1\nv %.9g %.9g -1\n", x0, y0, x1, y0,
                    x1, y1, x0, y1);
      os << buf << "f " << n + 1 << " " << n + 2 << " " << n + 3 << "\nf " << n + 1 << " " << n + 3 << " " << n + 4
         << "\n";
      n += 4;
    }
  return p;
}

// ---- Cases ----

struct StiffCase {
  const char* name;
  const char* xml;
  std::map<std::string, std::string> params;
  int res = 16;
  int spp_lo = 8;  // the convergence check renders spp_lo and 4 spp_lo against a PT reference
  int spp_ref = 512;
  double scale = 1;  // scene scale (camera motion of the tgpt animation scales with it)
  bool black = false;  // analytic answer: every layer exactly zero
  double uniform = 0;  // > 0: analytic answer, this radiance in every pixel (the reference)
  int seeds = 2;  // per budget in the convergence check (more for heavy-tailed cases)
};

inline std::vector<StiffCase> stiff_cases() {
  std::vector<StiffCase> v;
  v.push_back({"tiny_light", "tiny_light.xml", {}, 16, 8, 512});
  v.push_back({"rough_conductor", "rough_conductor.xml", {}, 16, 8, 4096});
  v.push_back({"mirror", "mirror.xml", {}, 16, 8, 4096});
  // Caustics through glass: heavy-tailed noise, so the convergence check starts at 16 spp.
  v.push_back({"glass", "glass.xml", {}, 16, 16, 4096});
  v.push_back({"tir", "tir.xml", {}, 16, 16, 1024});
  v.push_back({"grazing", "grazing.xml", {}, 16, 8, 512});
  v.push_back({"inside_object", "inside_object.xml", {}, 16, 4, 16, 1, /* black = */ true});
  v.push_back({"scale_1em4", "scaled.xml", {{"s", "1e-4"}, {"near", "1e-7"}, {"far", "1"}}, 16, 8, 2048, 1e-4});
  v.push_back({"scale_1e5", "scaled.xml", {{"s", "1e5"}, {"near", "100"}, {"far", "1e9"}}, 16, 8, 2048, 1e5});
  v.push_back({"degenerate_mesh", "degenerate.xml", {}, 16, 8, 512});
  // Le (1 - rho^1000) / (1 - rho), rho = 0.99: a PT reference would be noisier than G-PT at 128 spp.
  v.push_back({"furnace_depth1000", "furnace.xml", {}, 16, 8, 0, 1, false, (1.0 - std::pow(0.99, 1000)) / 0.01});
  // A sun 1e5 times the sky: the gradient methods' L2 error is heavy-tailed (the
  // solve spreads a firefly over the image; two seeds per budget read anything
  // from a 0.01 to a 1.3 ratio), so the convergence check averages 8 seeds.
  v.push_back({"hdr_sun_envmap", "envmap_sun.xml", {}, 16, 8, 512, 1, false, 0, 8});
  v.push_back({"all_shifts_fail", "checker.xml", {}, 16, 8, 256});
  return v;
}

// Parameters that point at runtime assets.
inline std::map<std::string, std::string> case_params(const StiffCase& c) {
  auto p = c.params;
  if (std::string(c.xml) == "envmap_sun.xml") p["envmap"] = sun_envmap_path();
  if (std::string(c.xml) == "checker.xml") p["mesh"] = checker_mesh_path(c.res);
  return p;
}

inline Expected<Scene> load_case(const StiffCase& c) {
  LoadOptions lo;
  lo.params = case_params(c);
  return load_mitsuba_scene(stiff_dir() + "/" + c.xml, lo);
}

// ---- Integrators ----

// kTgpt: the default temporal shift (replay); kTgptPathSpace: temporal_shift reconnect.
enum class Integ { kPt, kGptReplay, kGptReconnect, kGptHybrid, kTgpt, kTgptPathSpace };
inline bool is_tgpt(Integ i) { return i == Integ::kTgpt || i == Integ::kTgptPathSpace; }
inline const char* integ_name(Integ i) {
  switch (i) {
    case Integ::kPt: return "pt";
    case Integ::kGptReplay: return "gpt_replay";
    case Integ::kGptReconnect: return "gpt_reconnect";
    case Integ::kGptHybrid: return "gpt_hybrid";
    case Integ::kTgpt: return "tgpt";
    case Integ::kTgptPathSpace: return "tgpt_pathspace";
  }
  return "?";
}
inline const std::vector<Integ>& all_integrators() {
  static const std::vector<Integ> v = {Integ::kPt,         Integ::kGptReplay, Integ::kGptReconnect,
                                       Integ::kGptHybrid,  Integ::kTgpt,      Integ::kTgptPathSpace};
  return v;
}

// tgpt renders a 2-frame shot whose camera slides sideways (~0.01 room units
// per frame, sub-pixel) so that dt is sampled, not skipped as a static pair.
inline Animation camera_slide(const StiffCase& c) {
  Animation anim;
  auto desc = load_case(c);
  EXPECT_TRUE(desc.ok()) << desc.status().to_string();
  if (!desc.ok()) return anim;
  Track cam;
  cam.target = "sensor";
  const Transform t0 = desc->camera.to_world;
  const float step = float(0.24 * c.scale);  // per second; 24 fps
  cam.keys = {Keyframe{0.0, t0}, Keyframe{1.0, Transform::translate({step, 0, 0}) * t0}};
  anim.tracks.push_back(cam);
  return anim;
}

inline JobSpec make_job(const StiffCase& c, Integ integ, int spp, uint64_t seed) {
  JobSpec job;
  job.scene = c.xml;
  job.params = case_params(c);
  job.width = job.height = c.res;
  job.spp = spp;
  job.seed = seed;
  job.reconstruction.method = ReconMethod::kL2;
  job.outputs.previews = false;
  job.outputs.video_codec = "none";
  switch (integ) {
    case Integ::kPt: job.integrator = Integrator::kPt; break;
    case Integ::kGptReplay: job.integrator = Integrator::kGpt, job.shift = ShiftMapping::kReplay; break;
    case Integ::kGptReconnect: job.integrator = Integrator::kGpt, job.shift = ShiftMapping::kReconnect; break;
    case Integ::kGptHybrid: job.integrator = Integrator::kGpt, job.shift = ShiftMapping::kHybrid; break;
    case Integ::kTgpt:
    case Integ::kTgptPathSpace:
      job.integrator = Integrator::kTgpt;
      job.shift = ShiftMapping::kReconnect;
      job.temporal_shift =
          integ == Integ::kTgptPathSpace ? TemporalShiftMapping::kReconnect : TemporalShiftMapping::kReplay;
      job.frames = "0-1";
      job.reconstruction.window = 2;
      job.animation = camera_slide(c);
      break;
  }
  return job;
}

inline JobRunOptions run_options() {
  JobRunOptions o;
  o.base_dir = stiff_dir();
  o.threads = 2;
  return o;
}

inline std::vector<FrameOutput> run(const JobSpec& job) {
  std::vector<FrameOutput> out;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& f) { out.push_back(f); };
  Status st = run_job(job, run_options(), cb, nullptr);
  EXPECT_TRUE(st.ok()) << st.to_string();
  return out;
}

// PT reference of the same frames (same animation), cached per case and frame set.
inline const std::vector<Image>& pt_reference(const StiffCase& c, bool animated) {
  static std::map<std::string, std::vector<Image>> cache;
  const std::string key = std::string(c.name) + (animated ? "@anim" : "@still");
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  if (c.uniform > 0) {
    Image img(c.res, c.res, 3);
    for (float& v : img.data()) v = float(c.uniform);
    return cache[key] = std::vector<Image>(animated ? 2 : 1, img);
  }
  JobSpec job = make_job(c, animated ? Integ::kTgpt : Integ::kPt, c.spp_ref, 987654321);
  job.integrator = Integrator::kPt;
  std::vector<Image> ref;
  for (const FrameOutput& f : run(job)) ref.push_back(f.image.find("")->image);
  return cache[key] = ref;
}

// ---- Image checks ----

// Names every layer holding a NaN or Inf ("" when none).
inline std::string non_finite_layers(const FrameOutput& f) {
  std::string bad;
  for (const ImageLayer& l : f.image.layers) {
    size_t n = 0;
    for (float v : l.image.data())
      if (!std::isfinite(v)) ++n;
    if (n) bad += "'" + l.name + "' (" + std::to_string(n) + " values) ";
  }
  return bad;
}

// Per-pixel relMSE mean((I - R)^2 / (R^2 + 0.01)) over RGB (docs/report.md).
inline double rel_mse(const Image& img, const Image& ref) {
  double sum = 0;
  for (size_t k = 0; k < ref.data().size(); ++k) {
    double r = ref.data()[k], d = double(img.data()[k]) - r;
    sum += d * d / (r * r + 0.01);
  }
  return sum / double(ref.data().size());
}

// The same with the largest 1 % of the per-value terms dropped: a single
// firefly in a 16 x 16 image otherwise decides a convergence comparison.
inline double trimmed_rel_mse(const Image& img, const Image& ref) {
  std::vector<double> terms(ref.data().size());
  for (size_t k = 0; k < terms.size(); ++k) {
    double r = ref.data()[k], d = double(img.data()[k]) - r;
    terms[k] = d * d / (r * r + 0.01);
  }
  std::sort(terms.begin(), terms.end());
  const size_t keep = terms.size() - terms.size() / 100;
  double sum = 0;
  for (size_t k = 0; k < keep; ++k) sum += terms[k];
  return sum / double(keep);
}

inline double mean_of(const Image& img) {
  double s = 0;
  for (float v : img.data()) s += v;
  return s / double(img.data().size());
}

}  // namespace gdvr::stiff
