// Shared BSDF test configurations: every BSDF type at several incident angles
// (normal-ish, oblique, grazing; from below for transmissive and two-sided ones).
#pragma once

#include <cmath>
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/bsdf/bsdf.h"

namespace gdvr::testing {

struct BsdfCase {
  std::string name;  // gtest-safe: [A-Za-z0-9_]
  Bsdf bsdf;
  Vec3f wo;
};

inline Vec3f direction_with_cos(float cos_theta, float phi = 0.7f) {
  float s = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
  return {s * std::cos(phi), s * std::sin(phi), cos_theta};
}

inline Bsdf make_bsdf(BsdfType type, MicrofacetType dist = MicrofacetType::kBeckmann, float au = 0.1f,
                      float av = -1.0f) {
  Bsdf b;
  b.type = type;
  b.distribution = dist;
  b.alpha_u = au;
  b.alpha_v = av < 0 ? au : av;
  if (type == BsdfType::kPlastic || type == BsdfType::kRoughPlastic) {
    b.reflectance = Texture::constant(Rgb(0.8f, 0.4f, 0.2f));
    b.int_ior = 1.9f;
  }
  if (type == BsdfType::kDielectric || type == BsdfType::kRoughDielectric || type == BsdfType::kThinDielectric)
    b.int_ior = 1.5046f;  // Mitsuba's default "bk7"
  if (type == BsdfType::kConductor || type == BsdfType::kRoughConductor) {
    b.eta = Rgb(0.200438f, 0.924033f, 1.10221f);  // Cu, as in the veach-mis scene
    b.k = Rgb(3.91295f, 2.45285f, 2.14219f);
  }
  b.finalize();
  return b;
}

inline std::string angle_tag(float z) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%s%03d", z < 0 ? "below" : "z", int(std::round(std::abs(z) * 100)));
  return buf;
}

// One BSDF configuration (no incident direction yet).
struct BsdfConfig {
  std::string name;  // gtest-safe: [A-Za-z0-9_]
  Bsdf bsdf;
  bool from_below;  // also test incidence from below (transmissive, two-sided)
};

inline std::vector<BsdfConfig> all_bsdf_configs() {
  std::vector<BsdfConfig> configs;
  auto add = [&](std::string n, Bsdf b, bool below = false) { configs.push_back({std::move(n), b, below}); };
  using T = BsdfType;
  using M = MicrofacetType;
  add("diffuse", make_bsdf(T::kDiffuse));
  {
    Bsdf b = make_bsdf(T::kDiffuse);
    b.two_sided = true;
    add("twosided_diffuse", b, true);
  }
  add("conductor", make_bsdf(T::kConductor));
  add("roughconductor_beckmann_005", make_bsdf(T::kRoughConductor, M::kBeckmann, 0.05f));
  add("roughconductor_beckmann_030", make_bsdf(T::kRoughConductor, M::kBeckmann, 0.3f));
  add("roughconductor_ggx_010", make_bsdf(T::kRoughConductor, M::kGGX, 0.1f));
  add("roughconductor_ggx_050", make_bsdf(T::kRoughConductor, M::kGGX, 0.5f));
  add("roughconductor_ggx_aniso", make_bsdf(T::kRoughConductor, M::kGGX, 0.1f, 0.4f));
  add("roughconductor_beckmann_aniso", make_bsdf(T::kRoughConductor, M::kBeckmann, 0.3f, 0.08f));
  {
    Bsdf b = make_bsdf(T::kRoughConductor, M::kBeckmann, 0.2f);
    b.sample_visible = false;
    b.finalize();
    add("roughconductor_beckmann_allnormals", b);
    Bsdf t = make_bsdf(T::kRoughConductor, M::kBeckmann, 0.1f);
    t.two_sided = true;
    add("twosided_roughconductor", t, true);
  }
  add("plastic", make_bsdf(T::kPlastic));
  add("roughplastic_beckmann_010", make_bsdf(T::kRoughPlastic, M::kBeckmann, 0.1f));
  add("roughplastic_ggx_030", make_bsdf(T::kRoughPlastic, M::kGGX, 0.3f));
  add("dielectric", make_bsdf(T::kDielectric), true);
  add("roughdielectric_ggx_020", make_bsdf(T::kRoughDielectric, M::kGGX, 0.2f), true);
  add("roughdielectric_beckmann_020", make_bsdf(T::kRoughDielectric, M::kBeckmann, 0.2f), true);
  {
    Bsdf b = make_bsdf(T::kRoughDielectric, M::kGGX, 0.3f);
    b.sample_visible = false;
    b.finalize();
    add("roughdielectric_ggx_allnormals", b, true);
  }
  add("thindielectric", make_bsdf(T::kThinDielectric), true);
  return configs;
}

// Every configuration at every incident angle.
inline std::vector<BsdfCase> all_bsdf_cases() {
  std::vector<BsdfCase> cases;
  for (const BsdfConfig& p : all_bsdf_configs()) {
    std::vector<float> zs = {0.95f, 0.5f, 0.05f};
    if (p.from_below) {
      zs.push_back(-0.6f);
      zs.push_back(-0.95f);
    }
    for (float z : zs) cases.push_back({p.name + "_" + angle_tag(z), p.bsdf, direction_with_cos(z)});
  }
  return cases;
}

// Parameter lists for properties that only apply to some BSDFs, built by
// filtering the lists above, so that every instantiated test applies to its
// parameter and nothing is skipped at run time.
template <typename T, typename Pred>
std::vector<T> filtered(std::vector<T> all, Pred keep) {
  std::vector<T> out;
  for (T& c : all)
    if (keep(c.bsdf)) out.push_back(std::move(c));
  return out;
}

// Has a lobe with a density (diffuse or glossy): pdf()/eval() are not zero everywhere.
inline bool has_density(const Bsdf& b) { return !b.is_delta_only(); }
// Only Dirac lobes: sample() is the whole BSDF, eval()/pdf() are zero.
inline bool is_delta_only(const Bsdf& b) { return b.is_delta_only(); }
// Reflects only, with a density: eval() obeys Helmholtz reciprocity.
inline bool is_reflection_only_with_density(const Bsdf& b) {
  return has_density(b) && !b.has_lobe(kLobeTransmission);
}

inline std::vector<BsdfCase> density_cases() { return filtered(all_bsdf_cases(), has_density); }
inline std::vector<BsdfCase> delta_only_cases() { return filtered(all_bsdf_cases(), is_delta_only); }
inline std::vector<BsdfConfig> reflection_only_density_configs() {
  return filtered(all_bsdf_configs(), is_reflection_only_with_density);
}

// Readable names: for INSTANTIATE_TEST_SUITE_P's name generator ...
struct ParamName {
  template <typename P>
  std::string operator()(const ::testing::TestParamInfo<P>& info) const {
    return info.param.name;
  }
};

// ... and for gtest's value printer ("GetParam() = ...") instead of raw bytes.
inline void PrintTo(const BsdfCase& c, std::ostream* os) {
  *os << c.name << " (wo = " << c.wo.x << ", " << c.wo.y << ", " << c.wo.z << ")";
}
inline void PrintTo(const BsdfConfig& c, std::ostream* os) { *os << c.name; }

}  // namespace gdvr::testing
