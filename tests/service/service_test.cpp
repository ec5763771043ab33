// Integration tests: the real gdvr-server process on an ephemeral localhost
// port, driven over gRPC. Renders are tiny (cbox at 32x32, a few spp) so the
// suite stays fast on two cores.
#include <gtest/gtest.h>
#include <signal.h>

extern "C" {
#include <libavformat/avformat.h>
}

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/denoise/oidn_denoiser.h"
#include "core/io/image_io.h"
#include "core/job/job_runner.h"
#include "core/job/job_spec.h"
#include "tests/service/server_process.h"

namespace gdvr::testing {
namespace {
namespace fs = std::filesystem;
using grpc::StatusCode;

const char* kSmallJob = R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-3", "width": 32, "height": 32, "spp": 2, "seed": 7})";
// Slow enough per frame to kill or cancel mid-job on two cores.
const char* kSlowJob = R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-8", "width": 96, "height": 96, "spp": 48, "seed": 11})";

grpc::Status submit(v1::RenderService::Stub* stub, const std::string& key, const std::string& json,
                    v1::SubmitJobResponse* resp, const std::string& token = "") {
  grpc::ClientContext ctx;
  if (!token.empty()) ctx.AddMetadata("authorization", "Bearer " + token);
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  v1::SubmitJobRequest req;
  req.set_idempotency_key(key);
  req.set_job_json(json);
  return stub->SubmitJob(&ctx, req, resp);
}

struct Watched {
  std::map<int, std::string> exr;  // frame -> file bytes
  std::vector<int> order;
  std::map<int, std::vector<float>> raw;
  std::string terminal;  // completed | failed | cancelled | "" (stopped early)
  std::string reason;
  grpc::Status status;
};

// Watches from `from` (-1: start); stops after `stop_after` frames when > 0.
Watched watch(v1::RenderService::Stub* stub, const std::string& id, int from = -1, int stop_after = 0,
              bool raw = false) {
  Watched w;
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(240));
  v1::WatchJobRequest req;
  req.set_job_id(id);
  req.set_include_raw_rgb(raw);
  if (from >= 0) req.set_from_frame(from);
  auto reader = stub->WatchJob(&ctx, req);
  v1::JobEvent ev;
  std::string exr, rawbuf;
  while (reader->Read(&ev)) {
    if (ev.has_frame_final()) {
      const auto& f = ev.frame_final();
      EXPECT_LE(f.data().size(), size_t(1) << 20);
      if (f.payload() == v1::FrameFinal::PAYLOAD_EXR) {
        if (f.offset() == 0) exr.clear(), rawbuf.clear();
        EXPECT_EQ(f.offset(), exr.size());
        exr += f.data();
      } else {
        rawbuf += f.data();
      }
      if (f.last()) {
        EXPECT_EQ(f.stats().frame(), f.frame());
        w.exr[f.frame()] = exr;
        w.order.push_back(f.frame());
        if (raw) {
          std::vector<float> v(rawbuf.size() / 4);
          std::memcpy(v.data(), rawbuf.data(), v.size() * 4);
          w.raw[f.frame()] = v;
        }
        if (stop_after > 0 && int(w.order.size()) >= stop_after) {
          ctx.TryCancel();  // a client dropping mid-stream
          break;
        }
      }
    } else if (ev.has_completed()) {
      w.terminal = "completed";
    } else if (ev.has_failed()) {
      w.terminal = "failed", w.reason = ev.failed().reason();
    } else if (ev.has_cancelled()) {
      w.terminal = "cancelled", w.reason = ev.cancelled().reason();
    }
  }
  w.status = reader->Finish();
  return w;
}

LayeredImage decode(const std::string& exr_bytes, const std::string& tmp_path) {
  { std::ofstream(tmp_path, std::ios::binary) << exr_bytes; }
  auto img = read_exr(tmp_path);
  EXPECT_TRUE(img.ok()) << img.status().to_string();
  return img.ok() ? *img : LayeredImage{};
}

// What run_job itself produces for the job, in-process.
std::map<int, LayeredImage> reference(const std::string& json, const TestDir& dir) {
  auto job = parse_job_json(json, "reference");
  EXPECT_TRUE(job.ok()) << job.status().to_string();
  std::map<int, LayeredImage> out;
  JobRunOptions opts;
  opts.base_dir = dir.assets();
  opts.asset_root = dir.assets();
  // The server lends its jobs the build's denoiser (T-GPT's data term).
  opts.denoiser = make_job_denoiser(0, nullptr);
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& f) { out[f.frame] = f.image; };
  Status st = run_job(*job, opts, cb, nullptr);
  EXPECT_TRUE(st.ok()) << st.to_string();
  return out;
}

void expect_same(const LayeredImage& a, const LayeredImage& b, int frame) {
  ASSERT_EQ(a.layers.size(), b.layers.size()) << "frame " << frame;
  for (const auto& la : a.layers) {
    const ImageLayer* lb = b.find(la.name);
    ASSERT_NE(lb, nullptr) << "frame " << frame << " layer '" << la.name << "'";
    EXPECT_EQ(la.image.data(), lb->image.data()) << "frame " << frame << " layer '" << la.name << "' differs";
  }
}

v1::Job get_job(v1::RenderService::Stub* stub, const std::string& id) {
  grpc::ClientContext ctx;
  v1::GetJobRequest req;
  req.set_job_id(id);
  v1::Job job;
  EXPECT_TRUE(stub->GetJob(&ctx, req, &job).ok());
  return job;
}

// Frames (packets) of the one video stream in `path`; -1 when it does not open.
int video_frame_count(const std::string& path, int* width = nullptr, int* height = nullptr) {
  AVFormatContext* fmt = nullptr;
  if (avformat_open_input(&fmt, path.c_str(), nullptr, nullptr) != 0) return -1;
  int frames = -1;
  if (avformat_find_stream_info(fmt, nullptr) >= 0 && fmt->nb_streams == 1) {
    if (width) *width = fmt->streams[0]->codecpar->width;
    if (height) *height = fmt->streams[0]->codecpar->height;
    frames = 0;
    AVPacket* pkt = av_packet_alloc();
    while (av_read_frame(fmt, pkt) >= 0) {
      ++frames;
      av_packet_unref(pkt);
    }
    av_packet_free(&pkt);
  }
  avformat_close_input(&fmt);
  return frames;
}

std::string preview_name(int frame) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "preview_%04d.png", frame);
  return buf;
}

bool is_png(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  return in && std::string(sig, 8) == std::string("\x89PNG\r\n\x1a\n", 8);
}

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// FetchArtifacts into a map file name -> bytes.
std::map<std::string, std::string> fetch(v1::RenderService::Stub* stub, const std::string& id,
                                         std::vector<v1::ArtifactKind> kinds = {}) {
  grpc::ClientContext ctx;
  v1::FetchArtifactsRequest req;
  req.set_job_id(id);
  for (auto k : kinds) req.add_kinds(k);
  auto reader = stub->FetchArtifacts(&ctx, req);
  std::map<std::string, std::string> files;
  v1::ArtifactChunk c;
  while (reader->Read(&c)) {
    EXPECT_LE(c.data().size(), size_t(1) << 20);
    EXPECT_EQ(c.offset(), files[c.file_name()].size());
    files[c.file_name()] += c.data();
    if (c.last()) {
      EXPECT_EQ(files[c.file_name()].size(), c.total_size());
    }
  }
  grpc::Status st = reader->Finish();
  EXPECT_TRUE(st.ok()) << st.error_message();
  return files;
}

class ServiceTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(server_.start()) << "server did not start; log: " << server_.log_path(); }
  TestDir dir_;
  ServerProcess server_{dir_};
};

// ---- Submit, stream, compare ----

TEST_F(ServiceTest, StreamedFramesEqualRunJob) {
  auto stub = server_.stub();
  v1::SubmitJobResponse resp;
  ASSERT_TRUE(submit(stub.get(), "k1", kSmallJob, &resp).ok());
  Watched w = watch(stub.get(), resp.job_id(), -1, 0, /* raw = */ true);
  ASSERT_TRUE(w.status.ok()) << w.status.error_message();
  EXPECT_EQ(w.terminal, "completed");
  EXPECT_EQ(w.order, (std::vector<int>{1, 2, 3}));
  auto ref = reference(kSmallJob, dir_);
  for (int f : {1, 2, 3}) {
    LayeredImage got = decode(w.exr[f], dir_.path() + "/got.exr");
    expect_same(got, ref[f], f);
    // The streamed file is byte-identical to the one on the server's disk.
    std::ifstream in(dir_.out() + "/" + resp.job_id() + "/frame_000" + std::to_string(f) + ".exr", std::ios::binary);
    std::string disk((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(disk, w.exr[f]);
    const ImageLayer* main = ref[f].find("");
    ASSERT_NE(main, nullptr);
    ASSERT_EQ(w.raw[f].size(), main->image.pixel_count() * 3);
    EXPECT_EQ(w.raw[f][0], main->image.at(0, 0, 0));
  }
  EXPECT_TRUE(fs::exists(dir_.out() + "/" + resp.job_id() + "/stats.json"));
  EXPECT_EQ(get_job(stub.get(), resp.job_id()).state(), v1::JOB_STATE_COMPLETED);
}

TEST_F(ServiceTest, IdempotentSubmit) {
  auto stub = server_.stub();
  v1::SubmitJobResponse a, b, c;
  ASSERT_TRUE(submit(stub.get(), "same-key", kSmallJob, &a).ok());
  ASSERT_TRUE(submit(stub.get(), "same-key", kSmallJob, &b).ok());
  EXPECT_EQ(a.job_id(), b.job_id());
  EXPECT_FALSE(a.existing());
  EXPECT_TRUE(b.existing());
  grpc::Status st = submit(stub.get(), "same-key", kSlowJob, &c);
  EXPECT_EQ(st.error_code(), StatusCode::FAILED_PRECONDITION);
  EXPECT_NE(st.error_message().find("idempotency_key"), std::string::npos);
  grpc::ClientContext ctx;
  v1::ListJobsRequest lr;
  v1::ListJobsResponse list;
  ASSERT_TRUE(stub->ListJobs(&ctx, lr, &list).ok());
  EXPECT_EQ(list.jobs_size(), 1);
}

TEST_F(ServiceTest, CancelStopsRunningJob) {
  auto stub = server_.stub();
  v1::SubmitJobResponse resp;
  ASSERT_TRUE(submit(stub.get(), "c", kSlowJob, &resp).ok());
  Watched first = watch(stub.get(), resp.job_id(), -1, /* stop_after = */ 1);
  ASSERT_EQ(first.order.size(), 1u);
  grpc::ClientContext ctx;
  v1::CancelJobRequest req;
  req.set_job_id(resp.job_id());
  v1::Job job;
  ASSERT_TRUE(stub->CancelJob(&ctx, req, &job).ok());
  // The answer is the state the job is moving to, not a stale RUNNING.
  EXPECT_EQ(job.state(), v1::JOB_STATE_CANCELLING);
  Watched rest = watch(stub.get(), resp.job_id());
  EXPECT_EQ(rest.terminal, "cancelled");
  EXPECT_LT(rest.order.size(), 8u);
  EXPECT_EQ(get_job(stub.get(), resp.job_id()).state(), v1::JOB_STATE_CANCELLED);
  // Cancelling again is a precondition failure, not a crash.
  grpc::ClientContext ctx2;
  EXPECT_EQ(stub->CancelJob(&ctx2, req, &job).error_code(), StatusCode::FAILED_PRECONDITION);
}

TEST_F(ServiceTest, WatchResumesAfterDisconnect) {
  auto stub = server_.stub();
  v1::SubmitJobResponse resp;
  ASSERT_TRUE(submit(stub.get(), "r", kSlowJob, &resp).ok());
  Watched a = watch(stub.get(), resp.job_id(), -1, /* stop_after = */ 2);
  ASSERT_EQ(a.order, (std::vector<int>{1, 2}));
  Watched b = watch(stub.get(), resp.job_id(), a.order.back() + 1);
  EXPECT_EQ(b.terminal, "completed");
  EXPECT_EQ(b.order, (std::vector<int>{3, 4, 5, 6, 7, 8}));  // nothing missed, nothing repeated
  // The dropped watcher did not cancel the job.
  EXPECT_EQ(get_job(stub.get(), resp.job_id()).state(), v1::JOB_STATE_COMPLETED);
}

TEST_F(ServiceTest, KillNineAndRestartResumes) {
  std::string id;
  {
    auto stub = server_.stub();
    v1::SubmitJobResponse resp;
    ASSERT_TRUE(submit(stub.get(), "kill", kSlowJob, &resp).ok());
    id = resp.job_id();
    Watched a = watch(stub.get(), id, -1, /* stop_after = */ 2);
    ASSERT_EQ(a.order.size(), 2u);
  }
  server_.kill9();
  ASSERT_TRUE(server_.start());
  auto stub = server_.stub();
  Watched w = watch(stub.get(), id);
  ASSERT_TRUE(w.status.ok()) << w.status.error_message();
  EXPECT_EQ(w.terminal, "completed");
  EXPECT_EQ(w.order, (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8}));
  v1::Job job = get_job(stub.get(), id);
  EXPECT_EQ(job.final_frames_size(), 8);
  auto ref = reference(kSlowJob, dir_);
  for (int f = 1; f <= 8; ++f) expect_same(decode(w.exr[f], dir_.path() + "/got.exr"), ref[f], f);
  // The video was begun again after the restart (re-encoding the frames the
  // first run made final) and holds every frame once, in order.
  EXPECT_EQ(job.video_file(), "video.mp4");
  EXPECT_EQ(video_frame_count(dir_.out() + "/" + id + "/video.mp4"), 8);
  for (int f = 1; f <= 8; ++f) EXPECT_TRUE(is_png(dir_.out() + "/" + id + "/" + preview_name(f))) << f;
  // No stray temporary files left by the crash.
  for (const auto& e : fs::directory_iterator(dir_.out() + "/" + id)) {
    std::string name = e.path().filename().string();
    EXPECT_TRUE(e.path().extension() == ".exr" || e.path().extension() == ".png" || name == "video.mp4" ||
                name == "stats.json")
        << e.path();
  }
}

TEST_F(ServiceTest, SigtermShutsDownGracefully) {
  auto stub = server_.stub();
  v1::SubmitJobResponse resp;
  ASSERT_TRUE(submit(stub.get(), "t", kSlowJob, &resp).ok());
  (void)watch(stub.get(), resp.job_id(), -1, 1);
  EXPECT_EQ(server_.terminate(), 0);
  ASSERT_TRUE(server_.start());  // the job was checkpointed and resumes
  Watched w = watch(server_.stub().get(), resp.job_id());
  EXPECT_EQ(w.terminal, "completed");
  EXPECT_EQ(w.order.size(), 8u);
}

// ---- Bad input ----

struct BadCase {
  const char* name;
  std::string json;
  StatusCode code;
  const char* must_mention;
};

TEST_F(ServiceTest, BadInputsGetTheRightStatus) {
  { std::ofstream(dir_.assets() + "/broken.xml") << "<scene version=\"3.0.0\"><shape type="; }
  { std::ofstream(dir_.path() + "/outside.xml") << "<scene version=\"3.0.0\"/>"; }
  std::vector<BadCase> cases = {
      {"bad frame range", R"({"scene": "cbox/cbox-rgb.xml", "frames": "5-1"})", StatusCode::INVALID_ARGUMENT, "frames"},
      {"garbage frame range", R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-x"})", StatusCode::INVALID_ARGUMENT, "frames"},
      {"unknown field", R"({"scene": "cbox/cbox-rgb.xml", "colour": 3})", StatusCode::INVALID_ARGUMENT, "colour"},
      {"nested unknown field", R"({"scene": "cbox/cbox-rgb.xml", "outputs": {"codec": "h264"}})",
       StatusCode::INVALID_ARGUMENT, "outputs.codec"},
      {"missing scene", R"({"scene": "cbox/nope.xml"})", StatusCode::NOT_FOUND, "nope.xml"},
      {"outside asset root", R"({"scene": "../outside.xml"})", StatusCode::INVALID_ARGUMENT, "asset root"},
      {"absolute outside", R"({"scene": "/etc/passwd"})", StatusCode::INVALID_ARGUMENT, "asset root"},
      {"absurd resolution", R"({"scene": "cbox/cbox-rgb.xml", "width": 100000, "height": 100000})",
       StatusCode::RESOURCE_EXHAUSTED, "width"},
      {"negative spp", R"({"scene": "cbox/cbox-rgb.xml", "spp": -4})", StatusCode::INVALID_ARGUMENT, "spp"},
      {"malformed xml", R"({"scene": "broken.xml"})", StatusCode::INVALID_ARGUMENT, "broken.xml"},
      {"not json", "{scene:", StatusCode::INVALID_ARGUMENT, "JSON"},
      {"no scene", "{}", StatusCode::INVALID_ARGUMENT, "scene"},
      {"unknown integrator", R"({"scene": "cbox/cbox-rgb.xml", "integrator": "magic"})", StatusCode::INVALID_ARGUMENT,
       "integrator"},
      {"unknown OCIO view", R"({"scene": "cbox/cbox-rgb.xml", "outputs": {"ocio_view": "No Such View"}})",
       StatusCode::INVALID_ARGUMENT, "ocio"},
      {"unknown codec", R"({"scene": "cbox/cbox-rgb.xml", "outputs": {"video_codec": "vp9"}})",
       StatusCode::INVALID_ARGUMENT, "video_codec"},
      {"unknown EXR codec", R"({"scene": "cbox/cbox-rgb.xml", "outputs": {"exr_compression": "lzma"}})",
       StatusCode::INVALID_ARGUMENT, "exr_compression"},
      {"missing reference", R"({"scene": "cbox/cbox-rgb.xml", "reference": "cbox/nope.exr"})", StatusCode::NOT_FOUND,
       "reference"},
      {"reference outside root", R"({"scene": "cbox/cbox-rgb.xml", "reference": "../x.exr"})",
       StatusCode::INVALID_ARGUMENT, "reference"},
      {"reference pattern", R"({"scene": "cbox/cbox-rgb.xml", "reference": "ref_%s.exr"})",
       StatusCode::INVALID_ARGUMENT, "reference"},
  };
  auto stub = server_.stub();
  for (const auto& c : cases) {
    v1::SubmitJobResponse resp;
    grpc::Status st = submit(stub.get(), std::string("bad-") + c.name, c.json, &resp);
    EXPECT_EQ(st.error_code(), c.code) << c.name << ": " << st.error_message();
    EXPECT_NE(st.error_message().find(c.must_mention), std::string::npos)
        << c.name << ": message '" << st.error_message() << "' does not mention '" << c.must_mention << "'";
  }
  grpc::ClientContext ctx;
  v1::GetJobRequest req;
  req.set_job_id("job-unknown");
  v1::Job job;
  EXPECT_EQ(stub->GetJob(&ctx, req, &job).error_code(), StatusCode::NOT_FOUND);
  grpc::ClientContext wctx;
  v1::WatchJobRequest wreq;
  wreq.set_job_id("job-unknown");
  auto reader = stub->WatchJob(&wctx, wreq);
  v1::JobEvent ev;
  EXPECT_FALSE(reader->Read(&ev));
  EXPECT_EQ(reader->Finish().error_code(), StatusCode::NOT_FOUND);
  grpc::ClientContext lctx;
  v1::ListJobsRequest lreq;
  lreq.set_page_token("garbage");
  v1::ListJobsResponse lresp;
  EXPECT_EQ(stub->ListJobs(&lctx, lreq, &lresp).error_code(), StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(health_status(server_.channel()), "SERVING");
}

TEST(ServiceLimits, OversizedUploadAndQueueLimit) {
  TestDir dir;
  ServerProcess server(dir, {"--max-upload-bytes=1000", "--max-queue=1", "--concurrency=1"});
  ASSERT_TRUE(server.start());
  auto stub = server.stub();
  {
    grpc::ClientContext ctx;
    v1::UploadSceneResponse resp;
    auto writer = stub->UploadScene(&ctx, &resp);
    v1::UploadSceneChunk chunk;
    chunk.set_scene_file("scene.xml");
    chunk.set_path("scene.xml");
    chunk.set_data(std::string(4000, 'x'));
    writer->Write(chunk);
    writer->WritesDone();
    grpc::Status st = writer->Finish();
    EXPECT_EQ(st.error_code(), StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
    EXPECT_NE(st.error_message().find("upload"), std::string::npos);
  }
  {
    grpc::ClientContext ctx;
    v1::UploadSceneResponse resp;
    auto writer = stub->UploadScene(&ctx, &resp);
    v1::UploadSceneChunk chunk;
    chunk.set_scene_file("a.xml");
    chunk.set_path("../a.xml");
    chunk.set_data("<scene/>");
    writer->Write(chunk);
    writer->WritesDone();
    EXPECT_EQ(writer->Finish().error_code(), StatusCode::INVALID_ARGUMENT);
  }
  // Queue limit: one running + one queued fit; the third is refused.
  v1::SubmitJobResponse r;
  ASSERT_TRUE(submit(stub.get(), "q1", kSlowJob, &r).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // let it start
  grpc::Status st2 = submit(stub.get(), "q2", kSlowJob, &r);
  grpc::Status st3 = submit(stub.get(), "q3", kSlowJob, &r);
  EXPECT_TRUE(st2.ok() || st2.error_code() == StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(st3.error_code(), StatusCode::RESOURCE_EXHAUSTED) << st3.error_message();
  EXPECT_NE(st3.error_message().find("queue"), std::string::npos);
  EXPECT_EQ(health_status(server.channel()), "SERVING");
}

// ---- Auth ----

TEST(ServiceAuth, MissingOrWrongTokenIsUnauthenticated) {
  TestDir dir;
  ServerProcess server(dir, {}, {{"GDVR_TOKENS", "s3cret,other"}});
  ASSERT_TRUE(server.start());
  auto stub = server.stub();
  v1::SubmitJobResponse resp;
  grpc::Status none = submit(stub.get(), "a1", kSmallJob, &resp);
  EXPECT_EQ(none.error_code(), StatusCode::UNAUTHENTICATED) << none.error_message();
  grpc::Status wrong = submit(stub.get(), "a2", kSmallJob, &resp, "guess");
  EXPECT_EQ(wrong.error_code(), StatusCode::UNAUTHENTICATED);
  grpc::Status right = submit(stub.get(), "a3", kSmallJob, &resp, "s3cret");
  EXPECT_TRUE(right.ok()) << right.error_message();
  {
    grpc::ClientContext ctx;
    v1::WatchJobRequest req;
    req.set_job_id(resp.job_id());
    auto reader = stub->WatchJob(&ctx, req);
    v1::JobEvent ev;
    EXPECT_FALSE(reader->Read(&ev));
    EXPECT_EQ(reader->Finish().error_code(), StatusCode::UNAUTHENTICATED);
  }
  // Rejected calls did no work: only the authenticated job exists.
  grpc::ClientContext ctx;
  ctx.AddMetadata("authorization", "Bearer other");
  v1::ListJobsRequest lr;
  v1::ListJobsResponse list;
  ASSERT_TRUE(stub->ListJobs(&ctx, lr, &list).ok());
  EXPECT_EQ(list.jobs_size(), 1);
  EXPECT_EQ(health_status(server.channel()), "SERVING");  // probes need no token
}

// ---- Outputs: previews, video, artifacts ----

TEST_F(ServiceTest, PreviewsAndVideoPerJob) {
  auto stub = server_.stub();
  v1::SubmitJobResponse resp;
  ASSERT_TRUE(submit(stub.get(), "outputs", kSmallJob, &resp).ok());
  Watched w = watch(stub.get(), resp.job_id());
  ASSERT_EQ(w.terminal, "completed");
  const std::string dir = dir_.out() + "/" + resp.job_id();
  for (int f : {1, 2, 3}) EXPECT_TRUE(is_png(dir + "/" + preview_name(f))) << f;
  v1::Job job = get_job(stub.get(), resp.job_id());
  EXPECT_EQ(job.video_file(), "video.mp4");
  int width = 0, height = 0;
  EXPECT_EQ(video_frame_count(dir + "/video.mp4", &width, &height), 3);
  EXPECT_EQ(width, 32);
  EXPECT_EQ(height, 32);
  // FetchArtifacts returns exactly those files, byte for byte.
  auto files = fetch(stub.get(), resp.job_id());
  std::set<std::string> names;
  for (const auto& [name, bytes] : files) {
    names.insert(name);
    EXPECT_EQ(bytes, slurp(dir + "/" + name)) << name;
  }
  EXPECT_EQ(names, (std::set<std::string>{"frame_0001.exr", "frame_0002.exr", "frame_0003.exr", "preview_0001.png",
                                          "preview_0002.png", "preview_0003.png", "video.mp4", "stats.json"}));
  auto only_video = fetch(stub.get(), resp.job_id(), {v1::ARTIFACT_KIND_VIDEO});
  EXPECT_EQ(only_video.size(), 1u);
  EXPECT_EQ(only_video.count("video.mp4"), 1u);
}

TEST_F(ServiceTest, OtherCodecsAndNoOutputs) {
  auto stub = server_.stub();
  const std::string ffv1 =
      R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-2", "width": 32, "height": 32, "spp": 1, "outputs": {"video_codec": "ffv1"}})";
  const std::string none =
      R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-2", "width": 32, "height": 32, "spp": 1, "outputs": {"video_codec": "none", "previews": false}})";
  v1::SubmitJobResponse a, b;
  ASSERT_TRUE(submit(stub.get(), "ffv1", ffv1, &a).ok());
  ASSERT_TRUE(submit(stub.get(), "none", none, &b).ok());
  EXPECT_EQ(watch(stub.get(), a.job_id()).terminal, "completed");
  EXPECT_EQ(watch(stub.get(), b.job_id()).terminal, "completed");
  EXPECT_EQ(get_job(stub.get(), a.job_id()).video_file(), "video.mkv");
  EXPECT_EQ(video_frame_count(dir_.out() + "/" + a.job_id() + "/video.mkv"), 2);
  EXPECT_EQ(get_job(stub.get(), b.job_id()).video_file(), "");
  for (const auto& e : fs::directory_iterator(dir_.out() + "/" + b.job_id()))
    EXPECT_TRUE(e.path().extension() == ".exr" || e.path().filename() == "stats.json") << e.path();
}

// A reference image gives per-frame relMSE; a corrupt one is refused at submit.
TEST_F(ServiceTest, ReferenceImageRelMseAndCorruptReference) {
  auto ref = reference(kSmallJob, dir_);
  ASSERT_TRUE(write_exr(dir_.assets() + "/ref_0001.exr", ref[1]).ok());
  std::string job = R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-2", "width": 32, "height": 32, "spp": 2, "seed": 7, "reference": "ref_0001.exr"})";
  auto stub = server_.stub();
  v1::SubmitJobResponse resp;
  ASSERT_TRUE(submit(stub.get(), "ref", job, &resp).ok());
  ASSERT_EQ(watch(stub.get(), resp.job_id()).terminal, "completed");
  auto stats = nlohmann::json::parse(slurp(dir_.out() + "/" + resp.job_id() + "/stats.json"));
  ASSERT_EQ(stats["frames"].size(), 2u) << stats.dump();
  // Frame 1 is the reference itself: both relMSE forms are 0 against it.
  // Frame 2 (other samples) is not; a PT frame has no shift-failure rate.
  const auto& f1 = stats["frames"][0];
  const auto& f2 = stats["frames"][1];
  EXPECT_EQ(f1["frame"], 1);
  EXPECT_EQ(f1["rel_mse"], 0.0) << f1.dump();
  EXPECT_EQ(f1["rel_mse_global"], 0.0) << f1.dump();
  EXPECT_EQ(f1["shift_failure_rate"], -1.0) << f1.dump();
  EXPECT_GT(f2["rel_mse"].get<double>(), 0.0) << f2.dump();
  EXPECT_GT(f2["rel_mse_global"].get<double>(), 0.0) << f2.dump();

  { std::ofstream(dir_.assets() + "/garbage.exr", std::ios::binary) << "v/1\x01 this is not an OpenEXR file at all"; }
  std::ofstream(dir_.assets() + "/empty.exr").close();
  for (const char* name : {"garbage.exr", "empty.exr"}) {
    std::string bad = std::string(R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "reference": ")") + name + "\"}";
    grpc::Status st = submit(stub.get(), std::string("bad-ref-") + name, bad, &resp);
    EXPECT_EQ(st.error_code(), StatusCode::INVALID_ARGUMENT) << name << ": " << st.error_message();
    EXPECT_NE(st.error_message().find("reference"), std::string::npos) << st.error_message();
  }
  EXPECT_EQ(health_status(server_.channel()), "SERVING");
}

// ---- Several clients and jobs at once ----

TEST(ServiceConcurrency, TwoJobsThreeWatchersEach) {
  TestDir dir;
  ServerProcess server(dir, {"--concurrency=2"});
  ASSERT_TRUE(server.start()) << server.log_path();
  const std::vector<std::string> jobs = {
      R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-4", "width": 32, "height": 32, "spp": 4, "seed": 3})",
      R"({"scene": "cbox/cbox-rgb.xml", "frames": "10-14x2", "width": 40, "height": 24, "spp": 4, "seed": 5})"};
  const std::vector<std::vector<int>> expected = {{1, 2, 3, 4}, {10, 12, 14}};
  std::vector<std::string> ids;
  for (size_t j = 0; j < jobs.size(); ++j) {
    v1::SubmitJobResponse resp;
    auto stub = server.stub();
    ASSERT_TRUE(submit(stub.get(), "multi-" + std::to_string(j), jobs[j], &resp).ok());
    ids.push_back(resp.job_id());
  }
  // Three clients per job, each on its own channel, all at once.
  std::vector<Watched> results(6);
  std::vector<std::thread> threads;
  for (int c = 0; c < 6; ++c)
    threads.emplace_back([&, c] {
      auto stub = server.stub();
      results[size_t(c)] = watch(stub.get(), ids[size_t(c % 2)]);
    });
  for (auto& t : threads) t.join();
  for (int c = 0; c < 6; ++c) {
    const Watched& w = results[size_t(c)];
    size_t j = size_t(c % 2);
    EXPECT_TRUE(w.status.ok()) << w.status.error_message();
    EXPECT_EQ(w.terminal, "completed") << "client " << c;
    EXPECT_EQ(w.order, expected[j]) << "client " << c;
    for (int f : expected[j]) {
      char name[32];
      std::snprintf(name, sizeof name, "/frame_%04d.exr", f);
      EXPECT_EQ(w.exr.at(f), slurp(dir.out() + "/" + ids[j] + name)) << "client " << c << " frame " << f;
    }
  }
  auto stub = server.stub();
  for (const auto& id : ids) {
    v1::Job job = get_job(stub.get(), id);
    EXPECT_EQ(job.state(), v1::JOB_STATE_COMPLETED);
    EXPECT_EQ(video_frame_count(dir.out() + "/" + id + "/video.mp4"), job.frames_size());
  }
  EXPECT_EQ(health_status(server.channel()), "SERVING");
}

// ---- TLS with a bearer token ----

// A memory limit makes a T-GPT job spill its buffered frames to unnamed files
// and read them back by tiles: the streamed frames are the in-memory run's, and
// nothing is left in the spill folder.
TEST(ServiceMemoryLimit, SpilledTgptFramesEqualRunJob) {
  TestDir dir;
  const std::string spill = dir.path() + "/spill";
  fs::create_directories(spill);
  ServerProcess server(dir, {"--memory-limit-mib=0", "--spill-dir=" + spill});
  ASSERT_TRUE(server.start()) << "server did not start; log: " << server.log_path();
  const std::string job = R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-3", "width": 32, "height": 32, "spp": 2,
                              "seed": 7, "integrator": "tgpt",
                              "reconstruction": {"method": "l2", "window": 3, "tile_size": 16}})";
  auto stub = server.stub();
  v1::SubmitJobResponse resp;
  ASSERT_TRUE(submit(stub.get(), "spill", job, &resp).ok());
  Watched w = watch(stub.get(), resp.job_id(), -1, 0);
  ASSERT_TRUE(w.status.ok()) << w.status.error_message();
  EXPECT_EQ(w.terminal, "completed");
  auto ref = reference(job, dir);
  for (int f : {1, 2, 3}) {
    ASSERT_TRUE(w.exr.count(f)) << "frame " << f;
    expect_same(decode(w.exr[f], dir.path() + "/got.exr"), ref[f], f);
  }
  EXPECT_TRUE(fs::is_empty(spill));
}

TEST(ServiceTls, SelfSignedCertAndToken) {
  // deploy/install-deps.sh installs the openssl CLI; without it this test fails, never skips.
  ASSERT_EQ(std::system("command -v openssl >/dev/null 2>&1"), 0) << "the openssl CLI is not installed";
  TestDir dir;
  const std::string cert = dir.path() + "/cert.pem", key = dir.path() + "/key.pem";
  // A throwaway self-signed certificate for 127.0.0.1, made now with the
  // openssl CLI so no key material lives in the repository.
  std::string cmd = "openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj /CN=localhost "
                    "-addext subjectAltName=DNS:localhost,IP:127.0.0.1 -keyout " +
                    key + " -out " + cert + " >" + dir.path() + "/openssl.log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(dir.path() + "/openssl.log");
  ServerProcess server(dir, {"--tls-cert=" + cert, "--tls-key=" + key}, {{"GDVR_TOKENS", "tls-token"}});
  server.use_tls(slurp(cert));
  ASSERT_TRUE(server.start()) << slurp(server.log_path());
  auto stub = server.stub();

  v1::SubmitJobResponse resp;
  grpc::Status ok = submit(stub.get(), "tls1", kSmallJob, &resp, "tls-token");
  ASSERT_TRUE(ok.ok()) << ok.error_message();
  {
    grpc::ClientContext ctx;
    ctx.AddMetadata("authorization", "Bearer tls-token");
    v1::WatchJobRequest req;
    req.set_job_id(resp.job_id());
    auto reader = stub->WatchJob(&ctx, req);
    v1::JobEvent ev;
    int frames = 0;
    bool completed = false;
    while (reader->Read(&ev)) {
      frames += ev.has_frame_final() && ev.frame_final().last();
      completed |= ev.has_completed();
    }
    EXPECT_TRUE(reader->Finish().ok());
    EXPECT_TRUE(completed);
    EXPECT_EQ(frames, 3);
  }
  grpc::Status wrong = submit(stub.get(), "tls2", kSmallJob, &resp, "not-the-token");
  EXPECT_EQ(wrong.error_code(), StatusCode::UNAUTHENTICATED) << wrong.error_message();
  grpc::Status missing = submit(stub.get(), "tls3", kSmallJob, &resp);
  EXPECT_EQ(missing.error_code(), StatusCode::UNAUTHENTICATED) << missing.error_message();
  {
    grpc::ClientContext ctx;
    ctx.AddMetadata("authorization", "Bearer not-the-token");
    v1::ListJobsRequest lr;
    v1::ListJobsResponse list;
    EXPECT_EQ(stub->ListJobs(&ctx, lr, &list).error_code(), StatusCode::UNAUTHENTICATED);
  }
  // A plaintext client cannot talk to the TLS port at all.
  auto plain = v1::RenderService::NewStub(
      grpc::CreateChannel(server.address(), grpc::InsecureChannelCredentials()));
  grpc::Status st = submit(plain.get(), "tls4", kSmallJob, &resp, "tls-token");
  EXPECT_EQ(st.error_code(), StatusCode::UNAVAILABLE) << st.error_message();
  EXPECT_EQ(health_status(server.channel()), "SERVING");
}

}  // namespace
}  // namespace gdvr::testing
