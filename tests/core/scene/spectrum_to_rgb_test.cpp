// Spectra in scene files against the values Mitsuba 3.9.1 (scalar_rgb) gives
// the same XML (read back with mi.traverse): gdvr must turn a file's colours
// into the same RGB, or the two renderers disagree on any scene that gives
// its light as <spectrum value="5000"/>.
#include "core/scene/spectrum_to_rgb.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/scene/mitsuba_loader.h"

namespace gdvr {
namespace {

void expect_rgb(const Rgb& got, float r, float g, float b, float tol, const std::string& what) {
  EXPECT_NEAR(got.r, r, tol * std::max(1.0f, r)) << what;
  EXPECT_NEAR(got.g, g, tol * std::max(1.0f, g)) << what;
  EXPECT_NEAR(got.b, b, tol * std::max(1.0f, b)) << what;
}

Rgb list(const std::vector<double>& w, const std::vector<double>& v, SpectrumRole role) {
  Expected<Rgb> rgb = spectrum_list_to_rgb(w, v, role);
  EXPECT_TRUE(rgb.ok()) << rgb.status().to_string();
  return rgb.ok() ? *rgb : Rgb(-1.0f);
}

TEST(SpectrumToRgbTest, ConstantInsideAnEmitterIsEqualEnergyWhite) {
  expect_rgb(constant_spectrum_to_rgb(0.7f, SpectrumRole::kEmission), 0.843356f, 0.663804f, 0.636241f, 1e-5f, "0.7");
  expect_rgb(constant_spectrum_to_rgb(0.7f, SpectrumRole::kReflectance), 0.7f, 0.7f, 0.7f, 0, "0.7 reflectance");
}

TEST(SpectrumToRgbTest, ListsMatchMitsuba) {
  const SpectrumRole refl = SpectrumRole::kReflectance, emit = SpectrumRole::kEmission;
  expect_rgb(list({400, 700}, {1, 1}, refl), 0.995342f, 0.999756f, 0.994909f, 2e-5f, "flat 400-700");
  expect_rgb(list({400, 700}, {1, 1}, emit), 1.19969f, 0.94952f, 0.903443f, 2e-5f, "flat 400-700 emission");
  expect_rgb(list({360, 830}, {1, 1}, refl), 0.998985f, 0.998874f, 0.998802f, 2e-5f, "flat");
  expect_rgb(list({360, 830}, {1, 1}, emit), 1.20488f, 0.948228f, 0.909267f, 2e-5f, "flat emission");
  expect_rgb(list({400, 500, 600, 700}, {0.2, 0.5, 0.9, 0.3}, refl), 0.857641f, 0.683686f, 0.316548f, 2e-5f, "ramp");
  expect_rgb(list({400, 500, 600, 700}, {0.2, 0.5, 0.9, 0.3}, emit), 1.00232f, 0.6558f, 0.278267f, 2e-5f,
             "ramp emission");
  // Out of gamut: negatives clamp to 0; a reflectance clamps to 1, eta and k do not.
  expect_rgb(list({450, 460, 470}, {0, 5, 0}, emit), 0.00672458f, 0.0f, 0.813389f, 2e-5f, "narrow band");
  expect_rgb(list({400, 700}, {3, 3}, refl), 1, 1, 1, 0, "bright reflectance");
  expect_rgb(list({400, 700}, {3, 3}, SpectrumRole::kUnbounded), 2.98603f, 2.99927f, 2.98473f, 2e-5f, "eta");
}

TEST(SpectrumToRgbTest, MalformedListsAreErrors) {
  EXPECT_FALSE(spectrum_list_to_rgb({500}, {1}, SpectrumRole::kReflectance).ok());
  EXPECT_FALSE(spectrum_list_to_rgb({500, 400}, {1, 1}, SpectrumRole::kReflectance).ok());
  EXPECT_FALSE(spectrum_list_to_rgb({400, 400}, {1, 1}, SpectrumRole::kReflectance).ok());
  EXPECT_FALSE(spectrum_list_to_rgb({400, 500}, {1, NAN}, SpectrumRole::kReflectance).ok());
  std::vector<double> w, v;
  EXPECT_FALSE(parse_spd("400 1\n500\n", "x.spd", &w, &v).ok());
  w.clear(), v.clear();
  EXPECT_FALSE(parse_spd("400 1 2\n500 1\n", "x.spd", &w, &v).ok());
  w.clear(), v.clear();
  ASSERT_TRUE(parse_spd("# c\n400 0.2\n\n500 0.5 # c\r\n", "x.spd", &w, &v).ok());
  EXPECT_EQ(w, (std::vector<double>{400, 500}));
  EXPECT_EQ(v, (std::vector<double>{0.2, 0.5}));
}

// Through the loader: the role follows the element (inside <emitter> or not,
// eta/k unbounded), and .spd files resolve like any other scene file.
TEST(SpectrumToRgbTest, LoaderConvertsSpectraByRole) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(::testing::TempDir()) / "gdvr_spectrum_loader";
  fs::create_directories(dir);
  std::ofstream(dir / "ramp.spd") << "# ramp\n400 0.2\n500 0.5\n\n600 0.9 # peak\n700 0.3\n";
  const std::string xml = R"(<scene version="3.0.0">
  <bsdf type="diffuse" id="d"><spectrum name="reflectance" filename="ramp.spd"/></bsdf>
  <bsdf type="conductor" id="c"><spectrum name="eta" value="400:3, 700:3"/><spectrum name="k" value="2"/></bsdf>
  <shape type="rectangle"><ref id="d"/><emitter type="area"><spectrum name="radiance" value="5000"/></emitter></shape>
  <shape type="cube"><ref id="c"/></shape>
  <emitter type="point"><spectrum name="intensity" value="450:0, 460:5, 470:0"/></emitter>
  <emitter type="constant"><rgb name="radiance" value="5000"/></emitter>
</scene>)";
  auto s = load_mitsuba_scene_from_string(xml, dir.string(), {});
  ASSERT_TRUE(s.ok()) << s.status().to_string();
  expect_rgb(s->bsdfs[0].reflectance.value, 0.857641f, 0.683686f, 0.316548f, 2e-5f, "spd reflectance");
  expect_rgb(s->bsdfs[1].eta, 2.98603f, 2.99927f, 2.98473f, 2e-5f, "eta");
  expect_rgb(s->bsdfs[1].k, 2, 2, 2, 0, "constant k");
  expect_rgb(s->emitters[0].radiance, 5000 * 1.204794f, 5000 * 0.948291f, 5000 * 0.908916f, 1e-5f, "area");
  expect_rgb(s->emitters[1].intensity, 0.00672458f, 0.0f, 0.813389f, 2e-5f, "point");
  expect_rgb(s->emitters[2].radiance, 5000, 5000, 5000, 0, "rgb stays rgb");

  for (const char* bad : {R"(<spectrum name="reflectance" value="700:1, 400:1"/>)",
                          R"(<spectrum name="reflectance" value="400:1, 500"/>)",
                          R"(<spectrum name="reflectance" value="1" filename="ramp.spd"/>)",
                          R"(<spectrum name="reflectance" filename="missing.spd"/>)",
                          R"(<spectrum name="reflectance" filename="../outside.spd"/>)"}) {
    LoadOptions confined;
    confined.asset_root = dir.string();
    auto r = load_mitsuba_scene_from_string(
        std::string(R"(<scene version="3.0.0"><bsdf type="diffuse">)") + bad + "</bsdf></scene>", dir.string(), confined);
    EXPECT_FALSE(r.ok()) << bad;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace gdvr
