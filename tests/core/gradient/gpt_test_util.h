// Shared helpers of the G-PT tests: bundled scenes at tiny resolutions,
// converged PT references (cached per scene), image statistics.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <string>

#include "core/gradient/gpt_integrator.h"
#include "core/render/frame_scene.h"
#include "core/render/pt_integrator.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr::test {

struct TestScene {
  Scene desc;
  std::unique_ptr<FrameScene> scene;
  FrameRenderSettings render;
};

// `name`: "cbox" or "veach-mis" or "matpreview"; rendered at w x h.
inline std::shared_ptr<TestScene> load_test_scene(const std::string& name, int w, int h) {
  static std::map<std::string, std::shared_ptr<TestScene>> cache;
  const std::string key = name + "@" + std::to_string(w) + "x" + std::to_string(h);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  std::string xml = std::string(GDVR_SOURCE_DIR) + "/scenes/" +
                    (name == "cbox" ? "cbox/cbox-rgb.xml" : name + "/" + (name == "matpreview" ? "matpreview.xml" : "scene.xml"));
  LoadOptions load;
  if (name == "cbox") load.params = {{"res", std::to_string(w)}};
  else if (name == "veach-mis") load.params = {{"resx", std::to_string(w)}, {"resy", std::to_string(h)}};
  else load.params = {{"width", std::to_string(w)}, {"height", std::to_string(h)}};
  auto desc = load_mitsuba_scene(xml, load);
  if (!desc.ok()) {
    ADD_FAILURE() << desc.status().to_string();
    return nullptr;
  }
  auto ts = std::make_shared<TestScene>();
  ts->desc = std::move(desc.value());
  auto fs = FrameScene::create(ts->desc, {});
  if (!fs.ok()) {
    ADD_FAILURE() << fs.status().to_string();
    return nullptr;
  }
  ts->scene = std::move(fs.value());
  ts->render.width = w;
  ts->render.height = h;
  ts->render.path.max_depth = ts->desc.defaults.max_depth;
  ts->render.path.rr_depth = ts->desc.defaults.rr_depth;
  ts->render.threads = 2;
  ts->render.tile_size = 8;
  cache[key] = ts;
  return ts;
}

// Converged PT of the indirect part (color - direct) with its per-pixel variance; cached.
struct PtReference {
  Image indirect, variance;
};
inline const PtReference& pt_reference(const std::string& name, int w, int h, int spp) {
  static std::map<std::string, PtReference> cache;
  const std::string key = name + "@" + std::to_string(w) + "x" + std::to_string(h) + "@" + std::to_string(spp);
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  auto ts = load_test_scene(name, w, h);
  FrameRenderSettings rs = ts->render;
  rs.spp = spp;
  rs.seed = 987654321;
  auto r = render_frame_pt(*ts->scene, rs, 0, {});
  EXPECT_TRUE(r.ok());
  PtReference ref;
  ref.indirect = r->color;
  for (size_t k = 0; k < ref.indirect.data().size(); ++k) ref.indirect.data()[k] -= r->direct.data()[k];
  ref.variance = r->variance;
  return cache[key] = ref;
}

inline bool all_finite(const Image& img) {
  for (float v : img.data())
    if (!std::isfinite(v)) return false;
  return true;
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

}  // namespace gdvr::test
