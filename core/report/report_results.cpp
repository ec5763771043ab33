#include "core/report/report_results.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/io/atomic_file.h"
#include "core/report/denoiser_comparison.h"
#include "core/image/error_metrics.h"

namespace gdvr {
namespace {

double ratio(double num, double den) {
  return std::isfinite(num) && std::isfinite(den) && den > 0 ? num / den : kNoValue;
}

std::string csv_number(double v) {
  if (!std::isfinite(v)) return "";
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

std::string csv_text(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

nlohmann::json json_number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json json_numbers(const std::vector<double>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (double x : v) a.push_back(json_number(x));
  return a;
}

}  // namespace

void fill_equal_time_ratios(std::vector<ReportRow>* rows) {
  std::vector<std::pair<double, double>> pt_curve;
  for (const ReportRow& r : *rows)
    if (r.method == "pt") pt_curve.push_back({r.seconds_per_frame, r.rel_mse_global});
  for (ReportRow& r : *rows) {
    const ReportRow* pt = nullptr;
    for (const ReportRow& p : *rows)
      if (p.method == "pt" && p.budget_s == r.budget_s) pt = &p;
    if (pt) {
      r.equal_time_ratio_global = ratio(pt->rel_mse_global, r.rel_mse_global);
      r.equal_time_ratio_per_pixel = ratio(pt->rel_mse_per_pixel, r.rel_mse_per_pixel);
    }
    r.equal_time_ratio_interpolated = ratio(interpolate_log_log(pt_curve, r.seconds_per_frame), r.rel_mse_global);
  }
}

std::string results_csv(const std::vector<ReportRow>& rows) {
  std::ostringstream o;
  o << "method,integrator,reconstruction,budget_s,frames,seconds_per_frame,render_seconds,reconstruct_seconds,spp,"
       "rel_mse_global,rel_mse_per_pixel,flicker,shift_failure_rate,temporal_failure_rate,non_finite,"
       "equal_time_ratio_global,equal_time_ratio_per_pixel,equal_time_ratio_interpolated,"
       "predicted_improvement,achieved_improvement,denoise_seconds,feature_seconds,wall_seconds_per_frame\n";
  for (const ReportRow& r : rows) {
    o << csv_text(r.method) << ',' << csv_text(r.integrator) << ',' << csv_text(r.reconstruction) << ','
      << csv_number(r.budget_s) << ',' << r.frames << ',' << csv_number(r.seconds_per_frame) << ','
      << csv_number(r.render_seconds) << ',' << csv_number(r.reconstruct_seconds) << ',' << csv_number(r.spp) << ','
      << csv_number(r.rel_mse_global) << ',' << csv_number(r.rel_mse_per_pixel) << ',' << csv_number(r.flicker) << ','
      << csv_number(r.shift_failure_rate) << ',' << csv_number(r.temporal_failure_rate) << ','
      << csv_number(r.non_finite) << ',' << csv_number(r.equal_time_ratio_global) << ','
      << csv_number(r.equal_time_ratio_per_pixel) << ',' << csv_number(r.equal_time_ratio_interpolated) << ','
      << csv_number(r.predicted_improvement) << ',' << csv_number(r.achieved_improvement) << ','
      << csv_number(r.denoise_seconds) << ',' << csv_number(r.feature_seconds) << ','
      << csv_number(r.wall_seconds_per_frame) << '\n';
  }
  return o.str();
}

std::string results_json(const ReportMeta& meta, const std::vector<ReportRow>& rows) {
  nlohmann::json j;
  j["input"] = meta.input;
  j["frames"] = meta.frames;
  j["width"] = meta.width;
  j["height"] = meta.height;
  j["reference"] = {{"source", meta.reference_source}, {"path", meta.reference_path},
                    {"spp", meta.reference_spp}, {"render_seconds", meta.reference_seconds},
                    {"cached", meta.reference_cached},
                    {"noise_floor", {{"rel_mse_global", json_number(meta.reference_floor.global)},
                                     {"rel_mse_per_pixel", json_number(meta.reference_floor.per_pixel)},
                                     {"flicker", json_number(meta.reference_floor.flicker)}}}};
  j["machine"] = {{"threads", meta.threads}, {"loadavg", meta.load}};
  j["notes"] = meta.notes;
  j["rows"] = nlohmann::json::array();
  for (const ReportRow& r : rows) {
    nlohmann::json row = {
        {"method", r.method},
        {"integrator", r.integrator},
        {"reconstruction", r.reconstruction},
        {"budget_s", r.budget_s},
        {"frames", r.frames},
        {"seconds_per_frame", json_number(r.seconds_per_frame)},
        {"render_seconds", json_number(r.render_seconds)},
        {"reconstruct_seconds", json_number(r.reconstruct_seconds)},
        {"denoise_seconds", json_number(r.denoise_seconds)},
        {"feature_seconds", json_number(r.feature_seconds)},
        {"stage1_seconds", json_number(r.stage1_seconds)},
        {"wall_seconds_per_frame", json_number(r.wall_seconds_per_frame)},
        {"spp", json_number(r.spp)},
        {"rel_mse_global", json_number(r.rel_mse_global)},
        {"rel_mse_per_pixel", json_number(r.rel_mse_per_pixel)},
        {"flicker", json_number(r.flicker)},
        {"shift_failure_rate", json_number(r.shift_failure_rate)},
        {"temporal_failure_rate", json_number(r.temporal_failure_rate)},
        {"non_finite", r.non_finite},
        {"equal_time_ratio_global", json_number(r.equal_time_ratio_global)},
        {"equal_time_ratio_per_pixel", json_number(r.equal_time_ratio_per_pixel)},
        {"equal_time_ratio_interpolated", json_number(r.equal_time_ratio_interpolated)},
        {"predicted_improvement", json_number(r.predicted_improvement)},
        {"achieved_improvement", json_number(r.achieved_improvement)},
        {"frame_numbers", r.frame_numbers},
        {"frame_rel_mse_global", json_numbers(r.frame_rel_mse_global)},
        {"frame_rel_mse_per_pixel", json_numbers(r.frame_rel_mse_per_pixel)},
        {"left_out", r.left_out},
    };
    j["rows"].push_back(std::move(row));
  }
  j["denoiser_comparison"] = nlohmann::json::array();
  for (const DenoiserComparison& c : compare_with_denoisers(rows, meta.reference_floor)) {
    nlohmann::json cj = {{"method", c.method},
                         {"budget_s", c.budget_s},
                         {"baseline", c.baseline},
                         {"seconds_ratio", json_number(c.seconds_ratio)},
                         {"ratio_per_pixel", json_number(c.ratio_per_pixel)},
                         {"ratio_flicker", json_number(c.ratio_flicker)},
                         {"ratio_global", json_number(c.ratio_global)},
                         {"meets_per_pixel", c.meets_per_pixel},
                         {"meets_flicker", c.meets_flicker},
                         {"meets_global", c.meets_global},
                         {"equal_time", c.equal_time},
                         {"floor_well_below", c.floor_well_below},
                         {"floor_removed_per_pixel", json_number(c.floor_removed_per_pixel)},
                         {"floor_removed_flicker", json_number(c.floor_removed_flicker)},
                         {"floor_removed_global", json_number(c.floor_removed_global)},
                         {"meets_all", c.meets_all()}};
    j["denoiser_comparison"].push_back(std::move(cj));
  }
  return j.dump(2) + "\n";
}

Status write_text_file(const std::string& path, const std::string& text) {
  const std::string tmp = temporary_path_for(path);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) return internal_error("cannot write '" + tmp + "'");
    out << text;
    out.flush();
    if (!out) {
      discard_temporary(tmp);
      return internal_error("write to '" + tmp + "' failed");
    }
  }
  return commit_temporary(tmp, path);
}

}  // namespace gdvr
