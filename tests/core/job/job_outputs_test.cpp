// The output stage's layer selection (job.outputs.exr_layers) and the
// stats.json entry round trip. The front ends' agreement is tested end to end
// by tests/tools/output_stage_test.py.
#include "core/job/job_outputs.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "core/io/image_io.h"
#include "core/render/feature_buffers.h"
#include "core/scene/animation.h"

namespace gdvr {
namespace {

namespace fs = std::filesystem;

std::string demo_dir() { return std::string(GDVR_SOURCE_DIR) + "/scenes/demo"; }

JobSpec tiny_demo_job(const std::string& integrator) {
  JobSpec job;
  job.scene = "cbox_demo.xml";
  job.frames = "0-2";
  job.width = job.height = 12;
  job.spp = 1;
  job.seed = 5;
  job.integrator = parse_integrator(integrator).value();
  job.reconstruction.window = 3;
  job.outputs.previews = false;
  job.outputs.video_codec = "none";
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  job.animation.tracks.push_back(box);
  return job;
}

std::vector<FrameOutput> render(const JobSpec& job) {
  JobRunOptions options;
  options.base_dir = demo_dir();
  std::vector<FrameOutput> frames;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& out) { frames.push_back(out); };
  Status st = run_job(job, options, cb, nullptr);
  EXPECT_TRUE(st.ok()) << st.to_string();
  return frames;
}

fs::path fresh_dir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("gdvr_job_outputs_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// known_exr_layers() is what validate() accepts, so it must name every layer
// any integrator actually writes.
TEST(JobOutputsTest, KnownLayersNameEveryLayerTheIntegratorsWrite) {
  const auto& known = known_exr_layers();
  for (const char* integrator : {"pt", "gpt", "tgpt"}) {
    std::vector<FrameOutput> frames = render(tiny_demo_job(integrator));
    ASSERT_EQ(frames.size(), 3u) << integrator;
    for (const FrameOutput& f : frames) {
      ASSERT_NE(f.image.find(""), nullptr) << integrator;
      for (const ImageLayer& l : f.image.layers) {
        if (l.name.empty()) continue;
        EXPECT_NE(std::find(known.begin(), known.end(), l.name), known.end())
            << integrator << " writes layer '" << l.name << "' that known_exr_layers() lacks";
      }
    }
  }
}

// Every integrator's final frames carry the feature buffers, and the EXR
// names them as compositors expect: albedo.R/G/B, N.X/Y/Z and a bare Z.
TEST(JobOutputsTest, EveryIntegratorsFramesCarryTheFeatureBuffers) {
  for (const char* integrator : {"pt", "gpt", "tgpt"}) {
    SCOPED_TRACE(integrator);
    JobSpec job = tiny_demo_job(integrator);
    std::vector<FrameOutput> frames = render(job);
    ASSERT_EQ(frames.size(), 3u);
    fs::path dir = fresh_dir(std::string("features_") + integrator);
    auto outputs = JobOutputs::open(job, {0, 1, 2}, dir.string(), {});
    ASSERT_TRUE(outputs.ok()) << outputs.status().to_string();
    for (const FrameOutput& f : frames) {
      EXPECT_GT(f.stats.feature_seconds, 0.0);
      auto written = outputs.value()->write_frame(f);
      ASSERT_TRUE(written.ok()) << written.status().to_string();
      auto back = read_exr((dir / written->file).string());
      ASSERT_TRUE(back.ok()) << back.status().to_string();
      const ImageLayer* albedo = back->find("albedo");
      const ImageLayer* normal = back->find("N");
      const ImageLayer* depth = back->find("Z");
      ASSERT_TRUE(albedo && normal && depth);
      EXPECT_EQ(albedo->channels, (std::vector<std::string>{"R", "G", "B"}));
      EXPECT_EQ(normal->channels, (std::vector<std::string>{"X", "Y", "Z"}));
      EXPECT_EQ(depth->channels, (std::vector<std::string>{"Z"}));
      EXPECT_EQ(back->find("")->channels, (std::vector<std::string>{"R", "G", "B"}));
      for (float v : albedo->image.data()) {
        EXPECT_GE(v, 0.0f);
        EXPECT_LE(v, 1.0f);
      }
      // Distances, finite (kMissDepth where nothing is seen); the box's back
      // wall is in the middle of the view.
      for (float v : depth->image.data()) {
        EXPECT_GT(v, 0.0f);
        EXPECT_LE(v, kMissDepth);
      }
      EXPECT_LT(depth->image.at(6, 6, 0), kMissDepth);
      EXPECT_EQ(depth->image.data(), f.image.find("Z")->image.data());
    }
    fs::remove_all(dir);
  }
}

TEST(JobOutputsTest, ExrLayersKeepsTheImageAndTheSelectedLayers) {
  JobSpec job = tiny_demo_job("gpt");
  job.outputs.exr_layers = {"dx", "dt"};  // gpt has no dt: named in left_out
  std::vector<FrameOutput> frames = render(job);
  ASSERT_FALSE(frames.empty());
  // A selection without the feature buffers does not render them.
  EXPECT_EQ(frames[0].image.find("albedo"), nullptr);
  EXPECT_EQ(frames[0].stats.feature_seconds, 0.0);
  fs::path dir = fresh_dir("select");
  ASSERT_TRUE(JobOutputs::validate(job, {}, 0).ok());
  auto outputs = JobOutputs::open(job, {0, 1, 2}, dir.string(), {});
  ASSERT_TRUE(outputs.ok()) << outputs.status().to_string();
  auto written = outputs.value()->write_frame(frames[0]);
  ASSERT_TRUE(written.ok()) << written.status().to_string();
  auto back = read_exr((dir / written->file).string());
  ASSERT_TRUE(back.ok()) << back.status().to_string();
  std::set<std::string> names;
  for (const ImageLayer& l : back->layers) names.insert(l.name);
  EXPECT_EQ(names, (std::set<std::string>{"", "dx"}));
  const auto& left_out = written->stats.left_out;
  EXPECT_TRUE(std::any_of(left_out.begin(), left_out.end(),
                          [](const std::string& s) { return s.find("'dt'") != std::string::npos; }));
  // The main image is the one the whole frame holds.
  EXPECT_EQ(back->find("")->image.data(), frames[0].image.find("")->image.data());
  // Without a selection every layer is written.
  JobSpec all = tiny_demo_job("gpt");
  fs::path dir_all = fresh_dir("all");
  auto outputs_all = JobOutputs::open(all, {0, 1, 2}, dir_all.string(), {});
  ASSERT_TRUE(outputs_all.ok());
  ASSERT_TRUE(outputs_all.value()->write_frame(frames[0]).ok());
  auto back_all = read_exr((dir_all / frame_file_name(0)).string());
  ASSERT_TRUE(back_all.ok());
  EXPECT_EQ(back_all->layers.size(), frames[0].image.layers.size());
  fs::remove_all(dir);
  fs::remove_all(dir_all);
}

TEST(JobOutputsTest, UnknownOrRepeatedLayersAreRejectedWithTheFieldNamed) {
  JobSpec job = tiny_demo_job("tgpt");
  job.outputs.exr_layers = {"primal", "specular"};
  Status st = JobOutputs::validate(job, {}, 0);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("outputs.exr_layers[1]"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("specular"), std::string::npos) << st.message();
  job.outputs.exr_layers = {"dt", "dt"};
  st = JobOutputs::validate(job, {}, 0);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("listed twice"), std::string::npos) << st.message();
}

// A time budget's estimate of the output's cost writes a real EXR of the
// layers, and leaves nothing in the job's folder.
TEST(JobOutputsTest, WriteEstimateLeavesNothingBehind) {
  const fs::path dir = fresh_dir("write_estimate");
  JobSpec job = tiny_demo_job("pt");
  auto outputs = JobOutputs::open(job, {0}, dir.string(), {});
  ASSERT_TRUE(outputs.ok()) << outputs.status().to_string();
  LayeredImage layers;
  layers.add("primal", {"R", "G", "B"}, Image(16, 16, 3));
  layers.add("Z", {"Z"}, Image(16, 16, 1));
  EXPECT_GT(outputs.value()->estimate_write_seconds(layers), 0.0);
  EXPECT_TRUE(fs::is_empty(dir)) << "the probe EXR must be removed";
  fs::remove_all(dir);
}

TEST(JobOutputsTest, FrameEntryRoundTrips) {
  WrittenFrame w;
  w.file = "frame_0007.exr";
  w.bytes = 12345;
  w.stats.frame = 7;
  w.stats.render_seconds = 1.5;
  w.stats.spp = 16;
  w.stats.samples = 1u << 20;
  w.stats.rays = 5000000000ull;  // past 32 bits
  w.stats.temporal_rays = 42;
  w.stats.rel_mse = 0.25;
  w.stats.rel_mse_global = 0.125;
  w.stats.shift_failure_rate = 0.5;
  w.stats.left_out = {"temporal gradients: static shot"};
  auto back = parse_frame_entry(frame_entry_json(w));
  ASSERT_TRUE(back.ok()) << back.status().to_string();
  EXPECT_EQ(frame_entry_json(back.value()), frame_entry_json(w));
  EXPECT_EQ(back->stats.rays, 5000000000ull);
  EXPECT_EQ(parse_frame_entry("not json").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(parse_frame_entry(R"({"frame": "seven"})").status().code(), StatusCode::kInvalidArgument);
}

// "auto" spends a time budget's seconds on sampling rather than on ZIP.
TEST(JobOutputsTest, AutoCompressionIsRleUnderATimeBudgetAndZipOtherwise) {
  JobSpec job;
  EXPECT_EQ(job.outputs.exr_compression, "auto");
  EXPECT_EQ(frame_exr_compression(job), ExrCompression::kZip);
  job.time_budget_s = 0.3;
  EXPECT_EQ(frame_exr_compression(job), ExrCompression::kRle);
  job.outputs.exr_compression = "piz";  // named: kept, budget or not
  EXPECT_EQ(frame_exr_compression(job), ExrCompression::kPiz);
  job.time_budget_s = 0;
  EXPECT_EQ(frame_exr_compression(job), ExrCompression::kPiz);
}

}  // namespace
}  // namespace gdvr
