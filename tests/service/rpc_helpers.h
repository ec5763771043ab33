// Small RPC helpers shared by the service test files.
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "gdvr/v1/render_service.grpc.pb.h"

namespace gdvr::testing {

inline std::unique_ptr<grpc::ClientContext> rpc_context(const std::string& token = "", int deadline_s = 30) {
  auto ctx = std::make_unique<grpc::ClientContext>();
  if (!token.empty()) ctx->AddMetadata("authorization", "Bearer " + token);
  if (deadline_s > 0) ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(deadline_s));
  return ctx;
}

inline grpc::Status submit_json(v1::RenderService::Stub* stub, const std::string& key, const std::string& json,
                                v1::SubmitJobResponse* resp, const std::string& token = "") {
  auto ctx = rpc_context(token);
  v1::SubmitJobRequest req;
  req.set_idempotency_key(key);
  req.set_job_json(json);
  return stub->SubmitJob(ctx.get(), req, resp);
}

inline grpc::Status submit_spec(v1::RenderService::Stub* stub, const std::string& key, const v1::JobSpec& spec,
                                v1::SubmitJobResponse* resp, const std::string& token = "") {
  auto ctx = rpc_context(token);
  v1::SubmitJobRequest req;
  req.set_idempotency_key(key);
  *req.mutable_job() = spec;
  return stub->SubmitJob(ctx.get(), req, resp);
}

// One file of an upload: path and bytes (sent in one chunk).
struct UploadFile {
  std::string path, data;
};

inline grpc::Status upload(v1::RenderService::Stub* stub, const std::string& scene_file,
                           const std::vector<UploadFile>& files, v1::UploadSceneResponse* resp,
                           const std::string& token = "") {
  auto ctx = rpc_context(token);
  auto writer = stub->UploadScene(ctx.get(), resp);
  bool first = true;
  for (const auto& f : files) {
    v1::UploadSceneChunk c;
    if (first) c.set_scene_file(scene_file);
    first = false;
    c.set_path(f.path);
    c.set_data(f.data);
    if (!writer->Write(c)) break;
  }
  writer->WritesDone();
  return writer->Finish();
}

// Reads a job's events until its terminal event; returns that event's case
// name ("completed", "failed", "cancelled") or "" if the stream ended first.
inline std::string wait_terminal(v1::RenderService::Stub* stub, const std::string& id,
                                 const std::string& token = "") {
  auto ctx = rpc_context(token, 240);
  v1::WatchJobRequest req;
  req.set_job_id(id);
  auto reader = stub->WatchJob(ctx.get(), req);
  v1::JobEvent ev;
  std::string terminal;
  while (reader->Read(&ev)) {
    if (ev.has_completed()) terminal = "completed";
    if (ev.has_failed()) terminal = "failed";
    if (ev.has_cancelled()) terminal = "cancelled";
  }
  (void)reader->Finish();
  return terminal;
}

}  // namespace gdvr::testing
