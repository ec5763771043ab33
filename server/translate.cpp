#include "server/translate.h"

#include <google/protobuf/util/json_util.h>

#include <nlohmann/json.hpp>

#include "core/util/echo_text.h"

namespace gdvr::server {
namespace {

// Finds the first JSON key (dotted path) that `desc` does not declare, so the
// error names it; protobuf's own message ("Cannot find field.") does not.
std::string find_unknown_field(const nlohmann::json& j, const google::protobuf::Descriptor* desc,
                               const std::string& prefix) {
  if (!j.is_object() || !desc) return "";
  for (auto it = j.begin(); it != j.end(); ++it) {
    const auto* field = desc->FindFieldByName(it.key());
    if (!field) {  // protobuf JSON also accepts lowerCamelCase names
      for (int i = 0; i < desc->field_count() && !field; ++i)
        if (desc->field(i)->json_name() == it.key()) field = desc->field(i);
    }
    // Keys are the client's: echoed bounded (a 20,000-character key once
    // made a status too large for the client to receive).
    std::string path = prefix.empty() ? echo_text(it.key()) : prefix + "." + echo_text(it.key());
    if (!field) return path;
    if (field->is_map()) continue;
    if (field->message_type()) {
      if (field->is_repeated() && it->is_array()) {
        for (size_t i = 0; i < it->size(); ++i) {
          auto u = find_unknown_field((*it)[i], field->message_type(), path + "[" + std::to_string(i) + "]");
          if (!u.empty()) return u;
        }
      } else {
        auto u = find_unknown_field(*it, field->message_type(), path);
        if (!u.empty()) return u;
      }
    }
  }
  return "";
}

}  // namespace

std::string job_spec_to_json(const v1::JobSpec& spec) {
  google::protobuf::util::JsonPrintOptions opts;
  opts.preserve_proto_field_names = true;
  std::string text;
  (void)google::protobuf::util::MessageToJsonString(spec, &text, opts);
  auto j = nlohmann::json::parse(text, nullptr, /* allow_exceptions = */ false);
  if (j.is_object() && j.contains("seed") && j["seed"].is_string())
    j["seed"] = std::stoull(j["seed"].get<std::string>());
  return j.dump(2);
}

Expected<v1::JobSpec> job_spec_from_json(const std::string& json_text, const std::string& origin) {
  auto j = nlohmann::json::parse(json_text, nullptr, /* allow_exceptions = */ false);
  if (j.is_discarded()) return invalid_argument(origin + ": not valid JSON");
  if (!j.is_object()) return invalid_argument(origin + ": a job file is a JSON object");
  std::string unknown = find_unknown_field(j, v1::JobSpec::descriptor(), "");
  if (!unknown.empty()) return invalid_argument(origin + ": unknown field '" + unknown + "'");
  v1::JobSpec spec;
  auto st = google::protobuf::util::JsonStringToMessage(json_text, &spec);
  if (!st.ok()) return invalid_argument(origin + ": " + echo_text(std::string(st.message()), 2 * kEchoMaxChars));
  return spec;
}

Expected<JobSpec> to_core_job(const v1::JobSpec& spec) { return parse_job_json(job_spec_to_json(spec), "job"); }

void to_proto(const FrameStats& s, v1::FrameStats* out) {
  out->set_frame(s.frame);
  out->set_render_seconds(s.render_seconds);
  out->set_reconstruct_seconds(s.reconstruct_seconds);
  out->set_spp(s.spp);
  out->set_samples(s.samples);
  out->set_rays(s.rays);
  out->set_temporal_rays(s.temporal_rays);
  out->set_samples_per_second(s.samples_per_second);
  out->set_rays_per_second(s.rays_per_second);
  for (const auto& l : s.left_out) out->add_left_out(l);
  out->set_rel_mse(s.rel_mse);
  out->set_rel_mse_global(s.rel_mse_global);
  out->set_shift_failure_rate(s.shift_failure_rate);
  out->set_pass_a_spp(s.pass_a_spp);
  out->set_pass_b_spp(s.pass_b_spp);
  out->set_sampling_seconds(s.sampling_seconds);
  out->set_stage1_seconds(s.stage1_seconds);
}

FrameStats from_proto(const v1::FrameStats& s) {
  FrameStats out;
  out.frame = s.frame();
  out.render_seconds = s.render_seconds();
  out.reconstruct_seconds = s.reconstruct_seconds();
  out.spp = s.spp();
  out.samples = s.samples();
  out.rays = s.rays();
  out.temporal_rays = s.temporal_rays();
  out.samples_per_second = s.samples_per_second();
  out.rays_per_second = s.rays_per_second();
  out.left_out.assign(s.left_out().begin(), s.left_out().end());
  out.rel_mse = s.rel_mse();
  out.rel_mse_global = s.rel_mse_global();
  out.shift_failure_rate = s.shift_failure_rate();
  out.pass_a_spp = s.pass_a_spp();
  out.pass_b_spp = s.pass_b_spp();
  out.sampling_seconds = s.sampling_seconds();
  out.stage1_seconds = s.stage1_seconds();
  return out;
}

void to_proto(const JobProgress& p, v1::Progress* out) {
  out->set_frames_done(p.frames_done);
  out->set_frames_total(p.frames_total);
  out->set_fraction(p.fraction);
  out->set_eta_seconds(p.eta_seconds);
}

}  // namespace gdvr::server
