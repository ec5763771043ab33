// The farm's shared-folder protocol (core/farm/): job fingerprints, frame
// selection, buffers with their commit markers, temporaries and the
// finalize stage's stats.json. tests/farm/farm_test.py drives the same
// protocol through gdvr-farm processes on a localhost farm.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/farm/buffer_store.h"
#include "core/farm/farm_job.h"
#include "core/image/image_region.h"
#include "core/io/atomic_file.h"
#include "core/job/job_outputs.h"

namespace gdvr::farm {
namespace {

namespace fs = std::filesystem;

class FarmProtocolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("gdvr_farm_protocol_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "buffers");
    write("scene.xml", "<scene version=\"3.0.0\"/>");
  }
  void TearDown() override { fs::remove_all(dir_); }

  void write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }
  FarmJob job(const std::string& json_text) {
    write("job.json", json_text);
    auto j = load_job((dir_ / "job.json").string());
    EXPECT_TRUE(j.ok()) << j.status().to_string();
    return j.ok() ? j.value() : FarmJob{};
  }
  std::string buffers() const { return (dir_ / "buffers").string(); }

  static FrameBuffers some_buffers(int frame) {
    FrameBuffers fb;
    fb.frame = frame;
    Image primal(3, 2, 3);
    for (size_t i = 0; i < primal.data().size(); ++i) primal.data()[i] = 0.25f * float(i) + float(frame);
    fb.layers.add("primal", {"R", "G", "B"}, primal);
    fb.stats.frame = frame;
    fb.stats.render_seconds = 1.25;
    fb.stats.spp = 4;
    fb.stats.rays = 123456;
    return fb;
  }

  fs::path dir_;
};

TEST_F(FarmProtocolTest, FingerprintFollowsWhatTheRenderStageReads) {
  const std::string base = R"({"scene": "scene.xml", "frames": "0-9", "spp": 4)";
  const std::string fp = job(base + "}").fingerprint;
  ASSERT_EQ(fp.size(), 16u);
  // Fields only finalize or the server read leave it unchanged...
  EXPECT_EQ(job(base + R"(, "reconstruction": {"method": "l1"}, "priority": 3, "outputs": {"previews": false}})")
                .fingerprint,
            fp);
  EXPECT_EQ(job(R"({"scene": "scene.xml", "frames": "2-4", "spp": 4})").fingerprint, fp);
  // ...what the render stage reads changes it: the job and the scene's bytes.
  EXPECT_NE(job(R"({"scene": "scene.xml", "frames": "0-9", "spp": 8})").fingerprint, fp);
  write("scene.xml", "<scene version=\"3.0.0\"><!-- edited --></scene>");
  EXPECT_NE(job(base + "}").fingerprint, fp);
}

TEST_F(FarmProtocolTest, FramesAreSelectedByRangeOrChunk) {
  FarmJob j = job(R"({"scene": "scene.xml", "frames": "0-20x2"})");
  ASSERT_EQ(j.frames.size(), 11u);
  auto chunk = select_frames(j, {"", 4, 2});
  ASSERT_TRUE(chunk.ok());
  EXPECT_EQ(chunk.value(), (std::vector<int>{16, 18, 20}));
  EXPECT_EQ(select_frames(j, {"", 4, 3}).status().code(), StatusCode::kInvalidArgument);
  auto range = select_frames(j, {"3-8", 0, -1});  // intersected with the stepped range
  ASSERT_TRUE(range.ok());
  EXPECT_EQ(range.value(), (std::vector<int>{4, 6, 8}));
  EXPECT_EQ(select_frames(j, {"1", 0, -1}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(format_frames({0, 1, 2, 5, 7, 8}), "0-2,5,7-8");
  EXPECT_EQ(format_frames({}), "");
}

TEST_F(FarmProtocolTest, BuffersCountOnlyWithTheirMarkerAndTheirJob) {
  FarmJob j = job(R"({"scene": "scene.xml", "frames": "0-3"})");
  EXPECT_EQ(check_buffers(j, buffers(), 1).state, BufferState::kMissing);
  EXPECT_EQ(check_buffers(j, buffers(), 1).why, "not rendered yet");

  const FrameBuffers written = some_buffers(1);
  ASSERT_TRUE(write_buffers(j, buffers(), written).ok());
  BufferCheck c = check_buffers(j, buffers(), 1);
  ASSERT_EQ(c.state, BufferState::kComplete) << c.why;
  EXPECT_EQ(c.stats.rays, 123456u);
  auto back = read_buffers(j, buffers(), 1, 2);
  ASSERT_TRUE(back.ok()) << back.status().to_string();
  ASSERT_NE(back->layers.find("primal"), nullptr);
  EXPECT_EQ(back->layers.find("primal")->image.data(), written.layers.find("primal")->image.data());
  EXPECT_EQ(back->stats.spp, 4);
  // A tile task's view: the header now, each region read when asked for.
  auto opened = open_buffers(j, buffers(), 1, 2);
  ASSERT_TRUE(opened.ok()) << opened.status().to_string();
  EXPECT_TRUE(opened->layers.layers.empty());
  ASSERT_TRUE(opened->on_disk);
  const Image& primal = written.layers.find("primal")->image;
  EXPECT_EQ(opened->on_disk->width(), primal.width());
  EXPECT_EQ(opened->on_disk->height(), primal.height());
  const PixelRect rect{1, 1, primal.width(), primal.height()};
  auto region = opened->on_disk->read(rect);
  ASSERT_TRUE(region.ok()) << region.status().to_string();
  EXPECT_EQ(region->find("primal")->image.data(), crop_image(primal, rect).data());
  EXPECT_EQ(opened->stats.spp, 4);

  // Another job's buffers are refused, not mixed in.
  FarmJob other = job(R"({"scene": "scene.xml", "frames": "0-3", "spp": 99})");
  EXPECT_EQ(check_buffers(other, buffers(), 1).state, BufferState::kForeign);
  EXPECT_EQ(read_buffers(other, buffers(), 1, 1).status().code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(open_buffers(other, buffers(), 1, 1).status().code(), StatusCode::kFailedPrecondition);

  // An EXR cut short (copied in half) does not match its marker's size.
  const fs::path exr = dir_ / "buffers" / buffers_exr_name(1);
  fs::resize_file(exr, fs::file_size(exr) / 2);
  c = check_buffers(j, buffers(), 1);
  EXPECT_EQ(c.state, BufferState::kMissing);
  EXPECT_NE(c.why.find("bytes"), std::string::npos) << c.why;

  // Buffers without their marker (a worker killed between the two files).
  fs::remove(dir_ / "buffers" / buffers_json_name(1));
  c = check_buffers(j, buffers(), 1);
  EXPECT_EQ(c.state, BufferState::kMissing);
  EXPECT_NE(c.why.find("marker"), std::string::npos) << c.why;
  auto missing = read_buffers(j, buffers(), 1, 1);
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_NE(missing.status().message().find("gdvr-farm render"), std::string::npos);
  EXPECT_EQ(open_buffers(j, buffers(), 1, 1).status().code(), StatusCode::kNotFound);
}

// Farm files are written through core's temporaries, named with host and
// pid; a rerun on the same host sweeps what its dead predecessors left.
TEST_F(FarmProtocolTest, OnlyThisHostsDeadWritersTemporariesAreSwept) {
  pid_t dead = fork();
  if (dead == 0) _exit(0);
  ASSERT_GT(dead, 0);
  int status = 0;
  waitpid(dead, &status, 0);
  const std::string live = temporary_path_for((dir_ / "buffers_0001.exr").string());  // this process
  const std::string tag = live.substr(live.rfind(".tmp.") + 5);                        // "<host>.<pid>"
  const std::string host = tag.substr(0, tag.rfind('.'));
  const fs::path dead_ours = dir_ / ("buffers_0002.exr.tmp." + host + "." + std::to_string(dead));
  const fs::path theirs = dir_ / ("buffers_0003.exr.tmp.other-host." + std::to_string(dead));
  const fs::path not_a_temporary = dir_ / ("buffers_0004.exr.tmp." + host + "." + std::to_string(dead) + "x");
  for (const fs::path& p : {fs::path(live), dead_ours, theirs, not_a_temporary}) std::ofstream(p) << "half";
  remove_temporaries_of_dead_writers(dir_.string());
  EXPECT_TRUE(fs::exists(live)) << "a live writer's temporary was removed";
  EXPECT_FALSE(fs::exists(dead_ours));
  EXPECT_TRUE(fs::exists(theirs)) << "another host's temporary was removed";
  EXPECT_TRUE(fs::exists(not_a_temporary));
}

TEST_F(FarmProtocolTest, JobStatsListFinalFramesWithCurrentEntries) {
  FarmJob j = job(R"({"scene": "scene.xml", "frames": "0-2", "integrator": "gpt"})");
  const fs::path out = dir_ / "out";
  fs::create_directories(out);
  auto final_frame = [&](int f, uint64_t entry_bytes) {
    std::ofstream(out / frame_file_name(f), std::ios::binary) << std::string(100 + f, 'x');
    WrittenFrame w;
    w.file = frame_file_name(f);
    w.bytes = entry_bytes;
    w.stats.frame = f;
    w.stats.render_seconds = 2.0;
    ASSERT_TRUE(write_text_atomic((dir_ / "buffers" / final_stats_name(f)).string(), frame_entry_json(w)).ok());
  };
  final_frame(0, 100);
  final_frame(2, 999);  // stale: the frame was written again since
  ASSERT_TRUE(write_job_stats(j, buffers(), out.string()).ok());
  std::ifstream in(out / "stats.json");
  auto stats = nlohmann::json::parse(in);
  EXPECT_EQ(stats["state"], "partial");
  EXPECT_EQ(stats["integrator"], "gpt");
  EXPECT_EQ(stats["frames_total"], 3);
  ASSERT_EQ(stats["frames"].size(), 1u) << stats.dump();
  EXPECT_EQ(stats["frames"][0]["frame"], 0);
}

}  // namespace
}  // namespace gdvr::farm
