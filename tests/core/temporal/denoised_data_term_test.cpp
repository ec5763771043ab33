// T-GPT's denoised data term through the job runner (core/temporal/
// denoised_data_term.h): when it runs, what it says when it cannot, and
// what a failing denoiser does to a job. The denoisers here are stand-ins;
// OIDN's own tests are in tests/core/denoise.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

#include "core/job/job_runner.h"
#include "core/temporal/denoised_data_term.h"
#include "render_buffers.h"

namespace gdvr {
namespace {

std::string demo_dir() { return std::string(GDVR_SOURCE_DIR) + "/scenes/demo"; }

JobSpec tgpt_job(DataTerm data_term) {
  JobSpec job;
  job.scene = "cbox_demo.xml";
  job.frames = "0-3";
  job.width = job.height = 16;
  job.spp = 2;
  job.seed = 3;
  job.integrator = Integrator::kTgpt;
  job.reconstruction.method = ReconMethod::kL1;
  job.reconstruction.window = 4;
  job.reconstruction.data_term = data_term;
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  job.animation.tracks.push_back(box);
  return job;
}

struct JobRun {
  Status status;
  std::vector<FrameOutput> frames;
};

JobRun run(const JobSpec& job, FrameDenoiser denoiser) {
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.threads = 2;
  options.denoiser = std::move(denoiser);
  JobRun r;
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& f) { r.frames.push_back(f); };
  r.status = run_job(job, options, cb, nullptr);
  return r;
}

// A stand-in denoiser: a 3×3 box blur of the colour (it must change the image
// for the data term to matter), counting its calls.
FrameDenoiser box_blur(std::atomic<int>* calls) {
  return [calls](const Image& color, const Image& albedo, const Image& normal) -> Expected<Image> {
    ++*calls;
    EXPECT_EQ(albedo.width(), color.width());
    EXPECT_EQ(normal.height(), color.height());
    Image out(color.width(), color.height(), 3);
    for (int y = 0; y < color.height(); ++y)
      for (int x = 0; x < color.width(); ++x)
        for (int c = 0; c < 3; ++c) {
          float s = 0;
          int n = 0;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int u = x + dx, v = y + dy;
              if (u < 0 || v < 0 || u >= color.width() || v >= color.height()) continue;
              s += color.at(u, v, c), ++n;
            }
          out.at(x, y, c) = s / float(n);
        }
    return out;
  };
}

bool mentions(const FrameOutput& f, const std::string& text) {
  for (const std::string& s : f.stats.left_out)
    if (s.find(text) != std::string::npos) return true;
  return false;
}

void expect_finite(const FrameOutput& f) {
  for (const ImageLayer& l : f.image.layers)
    for (float v : l.image.data()) ASSERT_TRUE(std::isfinite(v)) << "frame " << f.frame << " layer " << l.name;
}

TEST(DenoisedDataTermTest, AutoDenoisesEveryFrameOnceWhenTheProcessHasADenoiser) {
  std::atomic<int> calls{0};
  JobRun with = run(tgpt_job(DataTerm::kAuto), box_blur(&calls));
  ASSERT_TRUE(with.status.ok()) << with.status.to_string();
  ASSERT_EQ(with.frames.size(), 4u);
  EXPECT_EQ(calls.load(), 4);
  JobRun sampled = run(tgpt_job(DataTerm::kSampled), box_blur(&calls));
  ASSERT_TRUE(sampled.status.ok()) << sampled.status.to_string();
  EXPECT_EQ(calls.load(), 4) << "a sampled data term never calls the denoiser";
  double diff = 0;
  for (size_t k = 0; k < 4; ++k) {
    expect_finite(with.frames[k]);
    EXPECT_FALSE(mentions(with.frames[k], "denoised data term"));
    const Image& a = with.frames[k].image.layers.front().image;
    const Image& b = sampled.frames[k].image.layers.front().image;
    ASSERT_EQ(a.data().size(), b.data().size());
    for (size_t i = 0; i < a.data().size(); ++i) diff += std::fabs(a.data()[i] - b.data()[i]);
  }
  EXPECT_GT(diff, 0.0) << "the denoised data term changed nothing";
}

TEST(DenoisedDataTermTest, AutoWithoutADenoiserUsesTheSampledPrimalAndSaysSo) {
  JobRun r = run(tgpt_job(DataTerm::kAuto), nullptr);
  ASSERT_TRUE(r.status.ok()) << r.status.to_string();
  ASSERT_EQ(r.frames.size(), 4u);
  for (const FrameOutput& f : r.frames) EXPECT_TRUE(mentions(f, "denoised data term: this process has no denoiser"));
  JobRun sampled = run(tgpt_job(DataTerm::kSampled), nullptr);
  ASSERT_TRUE(sampled.status.ok());
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_FALSE(mentions(sampled.frames[k], "denoised data term"));
    EXPECT_EQ(r.frames[k].image.layers.front().image.data(), sampled.frames[k].image.layers.front().image.data());
  }
}

TEST(DenoisedDataTermTest, DenoisedWithoutADenoiserIsAFailedPrecondition) {
  JobRunOptions options;
  options.base_dir = demo_dir();
  Status st = validate_job(tgpt_job(DataTerm::kDenoised), options);
  EXPECT_EQ(st.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(st.message().find("job.reconstruction.data_term"), std::string::npos) << st.message();
}

TEST(DenoisedDataTermTest, AFailingDenoiserFailsTheJobWithItsMessage) {
  JobRun failing = run(tgpt_job(DataTerm::kDenoised), [](const Image&, const Image&, const Image&) -> Expected<Image> {
    return internal_error("the denoiser's device is gone");
  });
  EXPECT_EQ(failing.status.code(), StatusCode::kInternal);
  EXPECT_NE(failing.status.message().find("the denoiser's device is gone"), std::string::npos)
      << failing.status.message();
  JobRun nan = run(tgpt_job(DataTerm::kDenoised), [](const Image& color, const Image&, const Image&) -> Expected<Image> {
    Image out = color;
    out.data()[5] = std::nanf("");
    return out;
  });
  EXPECT_EQ(nan.status.code(), StatusCode::kInternal);
  EXPECT_NE(nan.status.message().find("non-finite"), std::string::npos) << nan.status.message();
}

// Stage-1 buffers of `frames` as a farm's render task makes them, with or
// without a denoiser.
Status render_buffers(const JobSpec& job, FrameDenoiser denoiser, const std::vector<int>& frames,
                      std::map<int, FrameBuffers>* out) {
  JobRunOptions options;
  options.base_dir = demo_dir();
  options.threads = 2;
  options.denoiser = std::move(denoiser);
  return render_job_buffers(job, options, frames,
                            [&](FrameBuffers&& b) {
                              (*out)[b.frame] = std::move(b);
                              return Status::Ok();
                            },
                            nullptr, nullptr);
}

// The two layers travel with the frame's stage-1 buffers (as a farm's
// render task writes them): the data term and its one-channel trust map.
TEST(DenoisedDataTermTest, StageOneBuffersCarryTheDataTermLayers) {
  std::atomic<int> calls{0};
  std::map<int, FrameBuffers> out;
  Status st = render_buffers(tgpt_job(DataTerm::kDenoised), box_blur(&calls), {0, 1}, &out);
  ASSERT_TRUE(st.ok()) << st.to_string();
  ASSERT_EQ(out.size(), 2u);
  for (const auto& [f, b] : out) {
    const ImageLayer* d = b.layers.find(kDenoisedPrimalLayer);
    const ImageLayer* w = b.layers.find(kDataWeightLayer);
    ASSERT_TRUE(d && w) << "frame " << f;
    EXPECT_EQ(d->image.channels(), 3);
    EXPECT_EQ(w->image.channels(), 1);
    for (float v : w->image.data()) EXPECT_TRUE(v >= 1.0f && v <= 20.0f) << v;
  }
}

// A farm under data_term "auto" resolves it on each render machine: frames
// from a machine without a denoiser carry the sampled term. A window of both
// is refused with what to do, rather than solved under two rules.
TEST(DenoisedDataTermTest, AWindowOfMixedDataTermsIsRefusedNamingAFrameOfEach) {
  const JobSpec job = tgpt_job(DataTerm::kAuto);
  std::atomic<int> calls{0};
  std::map<int, FrameBuffers> buffers;
  ASSERT_TRUE(render_buffers(job, box_blur(&calls), {0, 1}, &buffers).ok());
  ASSERT_TRUE(render_buffers(job, nullptr, {2, 3}, &buffers).ok());
  ASSERT_EQ(buffers.size(), 4u);
  auto finalizer = JobFinalizer::create(job);
  ASSERT_TRUE(finalizer.ok()) << finalizer.status().to_string();
  auto mixed = finalizer.value()->finalize(0, buffers);
  ASSERT_FALSE(mixed.ok());
  EXPECT_EQ(mixed.status().code(), StatusCode::kFailedPrecondition);
  const std::string& why = mixed.status().message();
  EXPECT_NE(why.find("mixes data terms"), std::string::npos) << why;
  EXPECT_NE(why.find("frame 1's buffers carry the denoised data term"), std::string::npos) << why;
  EXPECT_NE(why.find("frame 3's do not"), std::string::npos) << why;

  // The same frames all rendered with the denoiser finalize.
  ASSERT_TRUE(render_buffers(job, box_blur(&calls), {2, 3}, &buffers).ok());
  auto again = JobFinalizer::create(job);
  ASSERT_TRUE(again.ok());
  auto one = again.value()->finalize(0, buffers);
  ASSERT_TRUE(one.ok()) << one.status().to_string();
  expect_finite(one.value());
}

// The data term is chosen again where the window is solved: a job that asks
// for the sampled one ignores a denoised term in its buffers (a farm's
// buffers re-finalized to compare), and one that asks for the denoised term
// refuses buffers without it rather than silently solving the sampled one.
TEST(DenoisedDataTermTest, TheSolveReadsTheDataTermTheJobAsksFor) {
  std::atomic<int> calls{0};
  std::map<int, FrameBuffers> denoised, sampled;
  ASSERT_TRUE(render_buffers(tgpt_job(DataTerm::kAuto), box_blur(&calls), {0, 1, 2, 3}, &denoised).ok());
  ASSERT_TRUE(render_buffers(tgpt_job(DataTerm::kAuto), nullptr, {0, 1, 2, 3}, &sampled).ok());
  ASSERT_TRUE(denoised.at(0).layers.find(kDenoisedPrimalLayer));
  ASSERT_FALSE(sampled.at(0).layers.find(kDenoisedPrimalLayer));
  auto finalize = [](DataTerm term, const std::map<int, FrameBuffers>& buffers) {
    auto finalizer = JobFinalizer::create(tgpt_job(term));
    EXPECT_TRUE(finalizer.ok()) << finalizer.status().to_string();
    return finalizer.value()->finalize(0, buffers);
  };
  auto ignored = finalize(DataTerm::kSampled, denoised);
  auto plain = finalize(DataTerm::kSampled, sampled);
  auto used = finalize(DataTerm::kAuto, denoised);
  ASSERT_TRUE(ignored.ok()) << ignored.status().to_string();
  ASSERT_TRUE(plain.ok()) << plain.status().to_string();
  ASSERT_TRUE(used.ok()) << used.status().to_string();
  const Image& a = ignored->image.layers.front().image;
  EXPECT_EQ(a.data(), plain->image.layers.front().image.data()) << "'sampled' must not read the denoised layers";
  EXPECT_NE(a.data(), used->image.layers.front().image.data()) << "'auto' reads them";

  auto missing = finalize(DataTerm::kDenoised, sampled);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(missing.status().message().find("frame 0: "), std::string::npos) << missing.status().message();
  EXPECT_NE(missing.status().message().find("carry no denoised data term"), std::string::npos)
      << missing.status().message();
}

}  // namespace
}  // namespace gdvr
