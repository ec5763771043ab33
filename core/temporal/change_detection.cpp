#include "core/temporal/change_detection.h"

namespace gdvr {
namespace {

bool same(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

std::string name_of(const std::string& id, size_t index) { return id.empty() ? "#" + std::to_string(index) : id; }

bool same_camera(const Camera& a, const Camera& b) {
  return a.to_world == b.to_world && a.fov == b.fov && a.fov_axis == b.fov_axis && a.near_clip == b.near_clip &&
         a.far_clip == b.far_clip;
}

bool same_emitter(const Emitter& a, const Emitter& b) {
  return a.type == b.type && a.to_world == b.to_world && same(a.radiance, b.radiance) &&
         same(a.intensity, b.intensity) && same(a.irradiance, b.irradiance) && a.cutoff_angle == b.cutoff_angle &&
         a.beam_width == b.beam_width && a.scale == b.scale && a.envmap == b.envmap && a.shape == b.shape;
}

// Scalar parameters only: textures are shared, immutable data after loading.
bool same_bsdf(const Bsdf& a, const Bsdf& b) {
  return a.type == b.type && a.two_sided == b.two_sided && same(a.eta, b.eta) && same(a.k, b.k) &&
         a.int_ior == b.int_ior && a.ext_ior == b.ext_ior && a.distribution == b.distribution &&
         a.alpha_u == b.alpha_u && a.alpha_v == b.alpha_v && a.lobes == b.lobes;
}

}  // namespace

std::string FramePairChanges::describe() const {
  if (!any()) return "nothing";
  std::string s;
  auto add = [&](const std::string& what) { s += (s.empty() ? "" : ", ") + what; };
  auto list = [](const char* kind, const std::vector<std::string>& names) {
    std::string r = kind;
    for (size_t i = 0; i < names.size(); ++i) r += (i ? "," : " ") + names[i];
    return r;
  };
  if (camera) add("camera");
  if (!shapes.empty()) add(list("shapes", shapes));
  if (!emitters.empty()) add(list("emitters", emitters));
  if (!materials.empty()) add(list("materials", materials));
  return s;
}

FramePairChanges detect_changes(const Scene& at_t, const Scene& at_next) {
  FramePairChanges c;
  c.camera = !same_camera(at_t.camera, at_next.camera);
  const size_t ns = std::min(at_t.shapes.size(), at_next.shapes.size());
  for (size_t i = 0; i < ns; ++i) {
    const Shape& a = at_t.shapes[i];
    const Shape& b = at_next.shapes[i];
    if (a.to_world != b.to_world || a.mesh != b.mesh || a.flip_normals != b.flip_normals) c.shapes.push_back(name_of(a.id, i));
    if (a.bsdf != b.bsdf) c.materials.push_back("shape " + name_of(a.id, i));
  }
  if (at_t.shapes.size() != at_next.shapes.size()) c.shapes.push_back("(shape count)");
  const size_t ne = std::min(at_t.emitters.size(), at_next.emitters.size());
  for (size_t i = 0; i < ne; ++i)
    if (!same_emitter(at_t.emitters[i], at_next.emitters[i])) c.emitters.push_back(name_of(at_t.emitters[i].id, i));
  if (at_t.emitters.size() != at_next.emitters.size()) c.emitters.push_back("(emitter count)");
  const size_t nb = std::min(at_t.bsdfs.size(), at_next.bsdfs.size());
  for (size_t i = 0; i < nb; ++i)
    if (!same_bsdf(at_t.bsdfs[i], at_next.bsdfs[i])) c.materials.push_back("#" + std::to_string(i));
  return c;
}

}  // namespace gdvr
