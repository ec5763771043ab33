#include "core/job/job_spec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "core/job/job_validation.h"
#include "core/scene/mitsuba_loader.h"

namespace gdvr {
namespace {

std::vector<int> frames(const std::string& text, size_t max = 0) {
  auto r = parse_frame_range(text, max);
  EXPECT_TRUE(r.ok()) << text << ": " << r.status().to_string();
  return r.ok() ? r.value() : std::vector<int>{};
}

TEST(FrameRangeTest, Forms) {
  EXPECT_EQ(frames("7"), (std::vector<int>{7}));
  EXPECT_EQ(frames("1-5"), (std::vector<int>{1, 2, 3, 4, 5}));
  EXPECT_EQ(frames("1-10x3"), (std::vector<int>{1, 4, 7, 10}));
  EXPECT_EQ(frames("1,5,10-12"), (std::vector<int>{1, 5, 10, 11, 12}));
  EXPECT_EQ(frames(" 3 - 4 , 1 ,4 "), (std::vector<int>{1, 3, 4}));
  EXPECT_EQ(frames("0"), (std::vector<int>{0}));
  EXPECT_EQ(frames("1-100").size(), 100u);
  EXPECT_EQ(frames("1-100x2").size(), 50u);
}

TEST(FrameRangeTest, Errors) {
  for (const char* bad : {"5-1", "x", "1-", "-3", "1-10x-2", "1-10x0", "", "1,,2", "a-b", "1.5", "3x2"}) {
    auto r = parse_frame_range(bad);
    EXPECT_FALSE(r.ok()) << "'" << bad << "' accepted";
  }
  auto r = parse_frame_range("1,5-1");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("5-1"), std::string::npos);
}

TEST(FrameRangeTest, TooManyFrames) {
  auto r = parse_frame_range("1-1000", 100);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kResourceExhausted);
  EXPECT_FALSE(parse_frame_range("0-999999999").ok());
  EXPECT_TRUE(parse_frame_range("1-100", 100).ok());
  // The largest int frame number is a range too large, not "not a number"
  // (it was, with 10 digits); a frame above it is named as too large.
  r = parse_frame_range("0-2147483647", 100);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(r.status().message().find("too large"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("2147483648 frames"), std::string::npos) << r.status().message();
  r = parse_frame_range("2147483648");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("too large"), std::string::npos) << r.status().message();
  EXPECT_EQ(frames("2147483647"), (std::vector<int>{2147483647}));
  // Through the job file the code survives, so the server answers RESOURCE_EXHAUSTED.
  auto job = parse_job_json(R"({"scene": "a.xml", "frames": "0-2147483647"})", "j.json");
  ASSERT_FALSE(job.ok());
  EXPECT_EQ(job.status().code(), StatusCode::kResourceExhausted);
  EXPECT_NE(job.status().message().find("job.frames"), std::string::npos) << job.status().message();
}

TEST(FrameRangeTest, HugeInputIsEchoedBounded) {
  std::string huge(20000, '7');
  huge += "x";
  auto r = parse_frame_range(huge);
  ASSERT_FALSE(r.ok());
  EXPECT_LT(r.status().message().size(), 1000u) << r.status().message().substr(0, 2000);
  EXPECT_NE(r.status().message().find("(20001 characters)"), std::string::npos);
}

TEST(JobSpecTest, ParsesEveryField) {
  auto job = parse_job_json(R"({
    "scene": "cbox/cbox-rgb.xml", "frames": "1-10x2", "fps": 30, "width": 320, "height": 240, "spp": 16,
    "time_budget_s": 2.5, "seed": "18446744073709551615", "integrator": "gpt", "shift": "hybrid",
    "reconstruction": {"method": "l2", "alpha": 0.5, "window": 5, "tile_size": 300,
                       "term_weights": [1, 1, 1, 2, 0.5, 0.5]},
    "params": {"spp": "8", "res": 64},
    "tracks": [{"target": "sensor", "interpolation": "cubic", "keys": [
      {"frame": 0, "lookat": {"origin": [0, 0, -5], "target": [0, 0, 0], "up": [0, 1, 0]}},
      {"time": 1, "translate": [1, 2, 3], "rotate": {"axis": [0, 0, 1], "angle": 90}, "scale": [2, 2, 2]},
      {"frame": 60, "matrix": [1,0,0,5, 0,1,0,0, 0,0,1,0, 0,0,0,1]}]}],
    "outputs": {"exr_layers": ["primal", "dx"], "exr_compression": "rle", "previews": false, "video_codec": "ffv1",
                "ocio_display": "d", "ocio_view": "v"},
    "priority": 3, "reference": "ref_%04d.exr", "direct_light": {"strata": 2, "edge_strata": 8}})",
                            "job.json");
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  EXPECT_EQ(job->scene, "cbox/cbox-rgb.xml");
  EXPECT_EQ(job->seed, 18446744073709551615ull);
  EXPECT_EQ(job->integrator, Integrator::kGpt);
  EXPECT_EQ(job->shift, ShiftMapping::kHybrid);
  EXPECT_EQ(job->reconstruction.method, ReconMethod::kL2);
  EXPECT_EQ(job->reconstruction.window, 5);
  EXPECT_EQ(job->reconstruction.tile_size, 300);
  EXPECT_EQ(parse_job_json(job_to_json(*job), "again")->reconstruction.tile_size, 300);
  EXPECT_EQ(job->reconstruction.term_weights, (std::vector<double>{1, 1, 1, 2, 0.5, 0.5}));
  EXPECT_EQ(parse_job_json(job_to_json(*job), "again")->reconstruction.term_weights, job->reconstruction.term_weights);
  EXPECT_EQ(job->params.at("res"), "64");
  ASSERT_EQ(job->animation.tracks.size(), 1u);
  const Track& t = job->animation.tracks[0];
  EXPECT_EQ(t.interpolation, Interpolation::kCubic);
  ASSERT_EQ(t.keys.size(), 3u);
  EXPECT_DOUBLE_EQ(t.keys[2].time, 2.0);  // frame 60 at 30 fps
  // translate * rotate * scale: (1,0,0) -> (2,0,0) -> (0,2,0) -> (1,4,3).
  Vec3f p = t.keys[1].to_world.point(Vec3f(1, 0, 0));
  EXPECT_NEAR(p.x, 1.0f, 1e-5f);
  EXPECT_NEAR(p.y, 4.0f, 1e-5f);
  EXPECT_NEAR(p.z, 3.0f, 1e-5f);
  EXPECT_FALSE(job->outputs.previews);
  EXPECT_EQ(job->outputs.exr_layers.size(), 2u);
  EXPECT_EQ(job->outputs.exr_compression, "rle");
  EXPECT_EQ(parse_job_json(job_to_json(*job), "again")->outputs.exr_compression, "rle");
  EXPECT_EQ(job->priority, 3);
  EXPECT_EQ(job->direct_light.strata, 2);
  EXPECT_EQ(job->direct_light.edge_strata, 8);
  // Unset means the integrator's default, and survives a round trip as unset.
  auto plain = parse_job_json(R"({"scene": "a.xml"})", "j");
  ASSERT_TRUE(plain.ok());
  EXPECT_FALSE(plain->direct_light.strata.has_value());
  auto again = parse_job_json(job_to_json(*plain), "again");
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(again->direct_light.strata.has_value());
  EXPECT_EQ(parse_job_json(job_to_json(*job), "again")->direct_light.edge_strata, 8);
}

// The defaults the public job format documents, taken from the settings that
// own them, and printed back under the same names.
TEST(JobSpecTest, DefaultsAreTheDocumentedOnes) {
  auto job = parse_job_json(R"({"scene": "a.xml"})", "j");
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  EXPECT_EQ(job->integrator, Integrator::kPt);
  EXPECT_EQ(job->shift, ShiftMapping::kReconnect);
  EXPECT_EQ(job->temporal_shift, TemporalShiftMapping::kReplay);
  EXPECT_EQ(job->reconstruction.method, ReconMethod::kL1);
  EXPECT_EQ(job->reconstruction.alpha, 0.2);
  EXPECT_EQ(job->reconstruction.window, 20);
  EXPECT_EQ(job->reconstruction.alpha, ReconSettings().alpha);
  EXPECT_EQ(job->reconstruction.window, TgptSettings().window);
  EXPECT_EQ(job->reconstruction.tile_size, ReconSettings().tile_size);
  EXPECT_EQ(job->reconstruction.data_term, DataTerm::kAuto);
  const std::string text = job_to_json(*job);
  for (const char* field : {R"("integrator": "pt")", R"("shift": "reconnect")", R"("temporal_shift": "replay")",
                            R"("method": "l1")", R"("data_term": "auto")"})
    EXPECT_NE(text.find(field), std::string::npos) << field << " in\n" << text;
}

// Every accepted spelling parses to its value and prints back unchanged.
TEST(JobSpecTest, NamesRoundTrip) {
  for (const auto& n : kIntegratorNames) {
    auto job = parse_job_json(std::string(R"({"scene": "a.xml", "integrator": ")") + n.name + "\"}", "j");
    ASSERT_TRUE(job.ok()) << n.name;
    EXPECT_EQ(job->integrator, n.value);
    EXPECT_NE(job_to_json(*job).find(std::string("\"") + n.name + "\""), std::string::npos);
  }
  for (const auto& n : kShiftMappingNames)
    EXPECT_EQ(parse_job_json(std::string(R"({"scene": "a.xml", "shift": ")") + n.name + "\"}", "j")->shift, n.value);
  for (const auto& n : kTemporalShiftNames)
    EXPECT_EQ(parse_job_json(std::string(R"({"scene": "a.xml", "temporal_shift": ")") + n.name + "\"}", "j")
                  ->temporal_shift,
              n.value);
  for (const auto& n : kReconMethodNames)
    EXPECT_EQ(parse_job_json(std::string(R"({"scene": "a.xml", "reconstruction": {"method": ")") + n.name + "\"}}",
                             "j")
                  ->reconstruction.method,
              n.value);
  for (const auto& n : kDataTermNames) {
    auto job = parse_job_json(std::string(R"({"scene": "a.xml", "integrator": "tgpt", "reconstruction": {"data_term": ")") + n.name +
                                  "\"}}",
                              "j");
    ASSERT_TRUE(job.ok()) << n.name;
    EXPECT_EQ(job->reconstruction.data_term, n.value);
    EXPECT_EQ(parse_job_json(job_to_json(*job), "again")->reconstruction.data_term, n.value);
  }
}

// An unknown name is refused with the field and the names it accepts.
TEST(JobSpecTest, UnknownNamesListTheAllowedOnes) {
  struct Case {
    const char* json;
    const char* field;
    const char* allowed;
  } cases[] = {
      {R"({"scene": "a.xml", "integrator": "bdpt"})", "job.integrator", "pt, gpt or tgpt, not 'bdpt'"},
      {R"({"scene": "a.xml", "shift": "sideways"})", "job.shift", "replay, reconnect or hybrid, not 'sideways'"},
      {R"({"scene": "a.xml", "temporal_shift": "warp"})", "job.temporal_shift", "replay or reconnect, not 'warp'"},
      {R"({"scene": "a.xml", "reconstruction": {"method": "l3"}})", "job.reconstruction.method",
       "l1, l2, uniform, weighted or none, not 'l3'"},
      {R"({"scene": "a.xml", "reconstruction": {"data_term": "blurred"}})", "job.reconstruction.data_term",
       "auto, sampled or denoised, not 'blurred'"},
      {R"({"scene": "a.xml", "integrator": 3})", "job.integrator", "must be a string"},
  };
  for (const Case& c : cases) {
    auto job = parse_job_json(c.json, "j.json");
    ASSERT_FALSE(job.ok()) << c.json;
    EXPECT_EQ(job.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(job.status().message().find(c.field), std::string::npos) << job.status().message();
    EXPECT_NE(job.status().message().find(c.allowed), std::string::npos) << job.status().message();
  }
}

// validate() checks a JobSpec however it was built (flags, code), with the
// messages the job file gets.
TEST(JobSpecTest, ValidateNamesTheField) {
  JobSpec job;
  job.scene = "a.xml";
  EXPECT_TRUE(validate(job).ok());
  auto expect_field = [](const JobSpec& j, const char* field) {
    Status st = validate(j);
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_EQ(st.message().rfind(field, 0), 0u) << st.message();
  };
  JobSpec bad = job;
  bad.scene.clear();
  expect_field(bad, "job.scene");
  bad = job;
  bad.width = kMaxJobResolution + 1;
  expect_field(bad, "job.width");
  bad = job;
  bad.spp = -1;
  expect_field(bad, "job.spp");
  bad = job;
  bad.time_budget_s = std::nan("");
  expect_field(bad, "job.time_budget_s");
  bad = job;
  bad.reconstruction.window = 0;
  expect_field(bad, "job.reconstruction.window");
  bad = job;
  bad.reconstruction.tile_size = 8;
  expect_field(bad, "job.reconstruction.tile_size");
  bad = job;
  bad.reconstruction.alpha = -1;
  expect_field(bad, "job.reconstruction.alpha");
  bad = job;
  bad.reconstruction.term_weights = {1, 1};
  expect_field(bad, "job.reconstruction.term_weights");
  bad = job;  // integrator pt
  bad.reconstruction.data_term = DataTerm::kDenoised;
  expect_field(bad, "job.reconstruction.data_term");
  bad.integrator = Integrator::kTgpt;  // the control variates weigh no data term
  bad.reconstruction.method = ReconMethod::kWeighted;
  expect_field(bad, "job.reconstruction.data_term");
  bad.reconstruction.method = ReconMethod::kL2;
  EXPECT_TRUE(validate(bad).ok());
  bad = job;
  bad.direct_light.edge_strata = kMaxDirectStrata + 1;
  expect_field(bad, "job.direct_light.edge_strata");
  bad = job;
  bad.outputs.video_codec = "gif";
  expect_field(bad, "job.outputs.video_codec");
  bad = job;
  bad.outputs.exr_compression = "dwaa";  // lossy: not offered
  expect_field(bad, "job.outputs.exr_compression");
  bad = job;
  bad.frames = "0-99999999";
  EXPECT_EQ(validate(bad).code(), StatusCode::kResourceExhausted);
}

TEST(JobSpecTest, RoundTrip) {
  auto job = parse_job_json(R"({"scene": "a.xml", "seed": 42, "frames": "0-3",
    "animation": {"tracks": [{"target": "box", "interpolation": "step",
      "keys": [{"time": 0, "translate": [1, 0, 0]}, {"time": 0.5, "rotate": {"axis": [1, 0, 0], "angle": 10}}]}]}})",
                            "job");
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  std::string text = job_to_json(*job);
  auto again = parse_job_json(text, "again");
  ASSERT_TRUE(again.ok()) << again.status().to_string() << "\n" << text;
  EXPECT_EQ(job_to_json(*again), text);
  EXPECT_EQ(again->seed, 42u);
  ASSERT_EQ(again->animation.tracks.size(), 1u);
  EXPECT_EQ(again->animation.tracks[0].keys[1].to_world, job->animation.tracks[0].keys[1].to_world);
  EXPECT_EQ(again->animation.tracks[0].interpolation, Interpolation::kStep);
}

TEST(JobSpecTest, UnknownFieldsNameTheirPath) {
  struct Case {
    const char* json;
    const char* path;
  } cases[] = {
      {R"({"scene": "a.xml", "sceen": 1})", "job.sceen: unknown field"},
      {R"({"scene": "a.xml", "reconstruction": {"alpah": 1}})", "job.reconstruction.alpah: unknown field"},
      {R"({"scene": "a.xml", "outputs": {"png": true}})", "job.outputs.png: unknown field"},
      {R"({"scene": "a.xml", "direct_light": {"stratum": 4}})", "job.direct_light.stratum: unknown field"},
      {R"({"scene": "a.xml", "tracks": [{"target": "sensor", "keys": [{"time": 0, "matrx": []}]}]})",
       "job.tracks[0].keys[0].matrx: unknown field"},
  };
  for (const Case& c : cases) {
    auto job = parse_job_json(c.json, "j.json");
    ASSERT_FALSE(job.ok()) << c.json;
    EXPECT_EQ(job.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(job.status().message().find(c.path), std::string::npos) << job.status().message();
  }
}

TEST(JobSpecTest, TypeAndValueErrorsNameTheField) {
  struct Case {
    const char* json;
    const char* needle;
  } cases[] = {
      {R"({"scene": "a.xml", "width": "wide"})", "job.width"},
      {R"({"scene": "a.xml", "fps": -1})", "job.fps"},
      {R"({"scene": "a.xml", "seed": "-1"})", "job.seed"},
      {R"({"scene": "a.xml", "frames": "5-1"})", "job.frames"},
      {R"({"scene": "a.xml", "integrator": "bdpt"})", "job.integrator"},
      {R"({"scene": "a.xml", "direct_light": {"strata": 65}})", "job.direct_light.strata"},
      {R"({"scene": "a.xml", "reconstruction": {"term_weights": [1, 1]}})", "job.reconstruction.term_weights"},
      {R"({"scene": "a.xml", "reconstruction": {"term_weights": [1, 1, 1, -1, 1, 1]}})", "job.reconstruction.term_weights[3]"},
      {R"({"scene": "a.xml", "reconstruction": {"term_weights": [0, 1, 1, 1, 1, 1]}})", "job.reconstruction.term_weights[0]"},
      {R"({"scene": "a.xml", "direct_light": {"edge_strata": -2}})", "job.direct_light.edge_strata"},
      // -1 is JobSpec's internal "unset"; written out it is as wrong as -2.
      {R"({"scene": "a.xml", "direct_light": {"strata": -1}})", "job.direct_light.strata"},
      {R"({"scene": "a.xml", "direct_light": {"edge_strata": -1}})", "job.direct_light.edge_strata"},
      {R"({"scene": "a.xml", "tracks": [{"target": "s", "interpolation": "spline", "keys": [{"time": 0, "translate": [0,0,0]}]}]})",
       "job.tracks[0].interpolation"},
      {R"({"scene": "a.xml", "tracks": [{"target": "s", "keys": [{"time": 1, "translate": [0,0,0]}, {"time": 0, "translate": [0,0,0]}]}]})",
       "job.tracks[0].keys[1]"},
      {R"({"scene": "a.xml", "tracks": [{"target": "s", "keys": [{"time": 0, "matrix": [1, 2]}]}]})", "matrix"},
      {R"({"frames": "1"})", "job.scene"},
      {R"([1, 2])", "job"},
      {R"({"scene": )", "not valid JSON"},
  };
  for (const Case& c : cases) {
    auto job = parse_job_json(c.json, "j.json");
    ASSERT_FALSE(job.ok()) << c.json;
    EXPECT_NE(job.status().message().find(c.needle), std::string::npos) << job.status().message();
  }
}

}  // namespace
}  // namespace gdvr

namespace gdvr {
namespace {

// The bundled demo job must parse and its tracks must address the demo scene.
TEST(JobSpecTest, DemoJobMatchesDemoScene) {
  std::string dir = std::string(GDVR_SOURCE_DIR) + "/scenes/demo/";
  std::ifstream in(dir + "demo_job.json");
  ASSERT_TRUE(in.good()) << "scenes/demo/demo_job.json is bundled and must exist";
  std::stringstream ss;
  ss << in.rdbuf();
  auto job = parse_job_json(ss.str(), "demo_job.json");
  ASSERT_TRUE(job.ok()) << job.status().to_string();
  auto scene = load_mitsuba_scene(dir + job->scene, {});
  ASSERT_TRUE(scene.ok()) << scene.status().to_string();
  ASSERT_TRUE(validate_animation(job->animation, *scene).ok());
  auto frames = parse_frame_range(job->frames);
  ASSERT_TRUE(frames.ok());
  for (int f : {frames->front(), frames->back()})
    ASSERT_TRUE(apply_animation(job->animation, f / job->fps, &*scene).ok());
}

}  // namespace
}  // namespace gdvr
