// The error-vs-time report end to end on the demo animation at a tiny size and
// tiny budgets: every method runs, the files are there, the numbers are sane,
// the reference is cached, and a supplied reference sequence gives the same
// errors as the cached one it copies.
#include "core/report/error_time_report.h"

#include <gtest/gtest.h>

#include "core/denoise/oidn_denoiser.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace gdvr {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

ErrorTimeReportOptions tiny_demo_report(const fs::path& out) {
  ErrorTimeReportOptions o;
  JobSpec& job = o.job;
  job.scene = "cbox_demo.xml";
  job.frames = "0-2";
  job.fps = 24;
  job.width = job.height = 16;
  job.seed = 5;
  Track box;
  box.target = "smallbox";
  box.keys = {Keyframe{0.0, Transform()}, Keyframe{1.0, Transform::translate({-70, 0, -60})}};
  job.animation.tracks.push_back(box);
  job.reconstruction.window = 3;
  o.run.base_dir = std::string(GDVR_SOURCE_DIR) + "/scenes/demo";
  o.run.threads = 2;
  o.input_name = "tiny demo";
  o.out_dir = out.string();
  o.reference_spp = 32;
  o.budgets = {0.04, 0.08};
  o.ocio_config = std::string(GDVR_SOURCE_DIR) + "/data/ocio/config.ocio";
  return o;
}

fs::path fresh_dir(const std::string& name) {
  fs::path d = fs::temp_directory_path() / ("gdvr_report_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  return d;
}

bool is_png(const fs::path& p) { return slurp(p).rfind("\x89PNG\r\n\x1a\n", 0) == 0; }

TEST(ErrorTimeReportTest, AnimationEndToEndWritesSaneResults) {
  const fs::path out = fresh_dir("anim");
  std::vector<std::string> log_lines;
  auto report = run_error_time_report(tiny_demo_report(out), [&](const std::string& l) { log_lines.push_back(l); },
                                      nullptr);
  ASSERT_TRUE(report.ok()) << report.status().to_string();
  EXPECT_FALSE(log_lines.empty());
  EXPECT_FALSE(report->meta.reference_cached);
  EXPECT_EQ(report->meta.width, 16);

  // Every method at every budget (the two denoised ones where OIDN is built in).
  const size_t methods = OidnDenoiser::available() ? 9 : 7;
  ASSERT_EQ(report->rows.size(), 2u * methods);
  for (const ReportRow& r : report->rows) {
    SCOPED_TRACE(r.method + " @ " + std::to_string(r.budget_s));
    EXPECT_EQ(r.frames, 3);
    EXPECT_GE(r.spp, 1.0);
    EXPECT_GT(r.seconds_per_frame, 0.0);
    // Sane errors: positive (noisy renders) and far below a black image's 1.
    EXPECT_GT(r.rel_mse_global, 0.0);
    EXPECT_LT(r.rel_mse_global, 0.5);
    EXPECT_GT(r.rel_mse_per_pixel, 0.0);
    EXPECT_TRUE(std::isfinite(r.flicker));
    EXPECT_GT(r.flicker, 0.0);
    EXPECT_EQ(r.non_finite, 0.0);
    ASSERT_EQ(r.frame_rel_mse_global.size(), 3u);
    if (r.integrator == "pt") {
      EXPECT_TRUE(std::isnan(r.shift_failure_rate));
      if (r.method == "pt") EXPECT_NEAR(r.equal_time_ratio_global, 1.0, 1e-12);
      else EXPECT_GT(r.equal_time_ratio_global, 0.0);  // pt-sd
      EXPECT_EQ(r.left_out.count("gradient sampling and reconstruction: integrator pt"), 1u);
    } else {
      EXPECT_GE(r.shift_failure_rate, 0.0);
      EXPECT_LE(r.shift_failure_rate, 1.0);
      EXPECT_GT(r.equal_time_ratio_global, 0.0);
      // Predicted from the variances: positive and finite (below 1 when the
      // gradients are noisier than the primal, as at a few spp).
      EXPECT_GT(r.predicted_improvement, 0.0);
      EXPECT_TRUE(std::isfinite(r.predicted_improvement));
      EXPECT_GT(r.achieved_improvement, 0.0);
    }
    if (r.integrator == "tgpt") {
      EXPECT_GE(r.temporal_failure_rate, 0.0);
      EXPECT_LE(r.temporal_failure_rate, 1.0);
    }
  }

  for (const char* f : {"results.csv", "results.json", "report.html", "plot_relmse_global.png",
                        "plot_relmse_per_pixel.png", "plot_flicker.png", "images/reference.png",
                        "images/pt_0p08s.png", "images/tgpt-l2_0p08s.png", "images/gpt-l2_shift_failures.png",
                        "images/tgpt-l1_temporal_failures.png"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_TRUE(is_png(out / "plot_relmse_global.png"));
  EXPECT_TRUE(is_png(out / "images/reference.png"));

  const std::string csv = slurp(out / "results.csv");
  EXPECT_EQ(size_t(std::count(csv.begin(), csv.end(), '\n')), 2 * methods + 1);
  auto j = nlohmann::json::parse(slurp(out / "results.json"));
  ASSERT_EQ(j["rows"].size(), 2 * methods);
  EXPECT_EQ(j["reference"]["spp"], 32);

  // The HTML is self-contained: relative images only, every image it names exists.
  const std::string html = slurp(out / "report.html");
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  for (const char* s : {"tgpt-l2", "gpt-weighted", "Predicted against achieved", "left out", "plot_flicker.png"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  for (size_t p = html.find("src=\""); p != std::string::npos; p = html.find("src=\"", p + 1)) {
    const size_t q = html.find('"', p + 5);
    EXPECT_TRUE(fs::exists(out / html.substr(p + 5, q - p - 5))) << html.substr(p + 5, q - p - 5);
  }

  // A second run reuses the cached reference.
  ErrorTimeReportOptions again = tiny_demo_report(out);
  again.methods = {"pt"};
  again.budgets = {0.04};
  auto second = run_error_time_report(again, nullptr, nullptr);
  ASSERT_TRUE(second.ok()) << second.status().to_string();
  EXPECT_TRUE(second->meta.reference_cached);
  ASSERT_EQ(second->rows.size(), 1u);

  // The cached reference handed back as a supplied sequence (pattern with %04d).
  const fs::path ref_dir = fs::path(second->meta.reference_path);
  ErrorTimeReportOptions supplied = again;
  supplied.reference = (ref_dir / "frame_%04d.exr").string();
  auto third = run_error_time_report(supplied, nullptr, nullptr);
  ASSERT_TRUE(third.ok()) << third.status().to_string();
  EXPECT_EQ(third->meta.reference_source, "supplied");
  EXPECT_GT(third->rows[0].rel_mse_global, 0.0);
  fs::remove_all(out);
}

TEST(ErrorTimeReportTest, StillSceneRunsNoTgptAndHasNoFlicker) {
  const fs::path out = fresh_dir("still");
  ErrorTimeReportOptions o = tiny_demo_report(out);
  o.job.frames = "1";
  o.budgets = {0.05};
  o.methods = {"pt", "gpt-l2", "tgpt-l2"};
  auto report = run_error_time_report(o, nullptr, nullptr);
  ASSERT_TRUE(report.ok()) << report.status().to_string();
  ASSERT_EQ(report->rows.size(), 2u);
  EXPECT_EQ(report->rows[1].method, "gpt-l2");
  for (const ReportRow& r : report->rows) EXPECT_TRUE(std::isnan(r.flicker));
  EXPECT_FALSE(fs::exists(out / "plot_flicker.png"));
  bool noted = false;
  for (const std::string& n : report->meta.notes) noted = noted || n.find("tgpt-l2: skipped") != std::string::npos;
  EXPECT_TRUE(noted);
  fs::remove_all(out);
}

#ifdef GDVR_HAVE_OIDN

// A 32×32 report at one budget of 0.15 s with the given frames and methods.
ErrorTimeReportOptions small_denoised_report(const fs::path& out, const std::string& frames,
                                             std::vector<std::string> methods) {
  ErrorTimeReportOptions o = tiny_demo_report(out);
  o.job.frames = frames;
  o.job.width = o.job.height = 32;
  o.budgets = {0.15};
  o.methods = std::move(methods);
  return o;
}

// PT + OIDN guided by albedo and normal at equal time: the feature pass and
// the denoiser come out of the budget, and both count in the row's time, as
// stage 1 and stage 2 do for every method.
TEST(ErrorTimeReportTest, DenoisedBaselinesCountFeaturesAndDenoisingInTheirTime) {
  const fs::path out = fresh_dir("oidn");
  auto report = run_error_time_report(small_denoised_report(out, "1", {"pt", "pt-oidn", "pt-sd-oidn"}), nullptr,
                                      nullptr);
  ASSERT_TRUE(report.ok()) << report.status().to_string();
  ASSERT_EQ(report->rows.size(), 3u);
  const ReportRow& pt = report->rows[0];
  EXPECT_EQ(pt.denoise_seconds, 0.0);
  for (const ReportRow& r : {report->rows[1], report->rows[2]}) {
    SCOPED_TRACE(r.method);
    EXPECT_EQ(r.integrator, "pt");
    EXPECT_GT(r.denoise_seconds, 0.0);
    EXPECT_NEAR(r.seconds_per_frame, r.stage1_seconds + r.reconstruct_seconds + r.denoise_seconds, 1e-9);
    EXPECT_GT(r.feature_seconds, 0.0);
    EXPECT_GE(r.stage1_seconds, r.render_seconds + r.feature_seconds);
    EXPECT_GE(r.wall_seconds_per_frame, r.seconds_per_frame);
    EXPECT_EQ(r.non_finite, 0.0);
    EXPECT_GE(r.spp, 1.0);
    // Sane: positive, far below a black image's 1. Whether the denoiser beats
    // PT depends on the budget (OIDNDenoiserTest checks it at a few spp).
    EXPECT_GT(r.rel_mse_global, 0.0);
    EXPECT_LT(r.rel_mse_global, 0.5);
  }
  EXPECT_EQ(report->rows[1].method, "pt-oidn");
  bool noted = false;
  for (const std::string& n : report->meta.notes) noted = noted || n.find("denoised methods: features") == 0;
  EXPECT_TRUE(noted);
  EXPECT_NE(slurp(out / "results.csv").find("denoise_seconds"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "images/pt-oidn_0p15s.png"));
  fs::remove_all(out);
}

// tgpt-l1-oidn denoises tgpt-l1's reconstructed frames again, its time
// counted like the baselines'; it is asked for, never a default run.
TEST(ErrorTimeReportTest, TgptFollowedByOidnCountsItsDenoising) {
  const fs::path out = fresh_dir("tgpt_oidn");
  auto report =
      run_error_time_report(small_denoised_report(out, "0-1", {"tgpt-l1", "tgpt-l1-oidn"}), nullptr, nullptr);
  ASSERT_TRUE(report.ok()) << report.status().to_string();
  ASSERT_EQ(report->rows.size(), 2u);
  const ReportRow& plain = report->rows[0];
  const ReportRow& denoised = report->rows[1];
  EXPECT_EQ(denoised.method, "tgpt-l1-oidn");
  EXPECT_EQ(denoised.integrator, "tgpt");
  EXPECT_EQ(plain.denoise_seconds, 0.0);
  EXPECT_GT(denoised.denoise_seconds, 0.0);
  EXPECT_NEAR(denoised.seconds_per_frame,
              denoised.stage1_seconds + denoised.reconstruct_seconds + denoised.denoise_seconds, 1e-9);
  EXPECT_EQ(denoised.non_finite, 0.0);
  EXPECT_GT(denoised.rel_mse_global, 0.0);
  EXPECT_LT(denoised.rel_mse_global, 0.5);
  EXPECT_TRUE(fs::exists(out / "images/tgpt-l1-oidn_0p15s.png"));
  fs::remove_all(out);
}

#else

TEST(ErrorTimeReportTest, DenoisedBaselinesNeedABuildWithOidn) {
  const fs::path out = fresh_dir("no_oidn");
  ErrorTimeReportOptions o = tiny_demo_report(out);
  o.methods = {"pt", "pt-oidn"};
  auto r = run_error_time_report(o, nullptr, nullptr);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kUnimplemented);
  EXPECT_NE(r.status().message().find("pt-oidn"), std::string::npos) << r.status().message();
  EXPECT_NE(r.status().message().find("built without Intel Open Image Denoise"), std::string::npos);
  fs::remove_all(out);
}

#endif

TEST(ErrorTimeReportTest, BadInputsAreNamedErrors) {
  const fs::path out = fresh_dir("bad");
  ErrorTimeReportOptions o = tiny_demo_report(out);
  o.reference = "/nonexistent/single.exr";  // one file for three frames
  auto r = run_error_time_report(o, nullptr, nullptr);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("%d"), std::string::npos) << r.status().message();

  o = tiny_demo_report(out);
  o.methods = {"pt", "bdpt"};
  r = run_error_time_report(o, nullptr, nullptr);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("bdpt"), std::string::npos);

  o = tiny_demo_report(out);
  o.budgets = {1, -2};
  EXPECT_FALSE(run_error_time_report(o, nullptr, nullptr).ok());

  o = tiny_demo_report(out);
  std::atomic<bool> cancel{true};
  r = run_error_time_report(o, nullptr, &cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kCancelled);
  fs::remove_all(out);
}

}  // namespace
}  // namespace gdvr
