#include "server/render_service.h"

#include <fstream>
#include <vector>

#include "core/util/echo_text.h"
#include "server/log.h"
#include "server/scene_upload.h"
#include "server/status_map.h"
#include "server/translate.h"

namespace gdvr::server {

// The log gets the message as it is (absolute paths and all, bounded by
// log_event); the client gets it through the ClientMessageFilter.
grpc::Status RenderServiceImpl::logged(const char* rpc, const std::string& job, const grpc::Status& st) const {
  if (st.ok()) return st;
  log_event("warn", "rpc_error", {{"rpc", rpc}, {"job", job}, {"code", grpc_code_name(st.error_code())},
                                  {"message", st.error_message()}});
  return grpc::Status(st.error_code(), jobs_->client_text()(st.error_message()));
}

grpc::Status RenderServiceImpl::check_auth(grpc::ServerContext* ctx) const {
  if (auth_ && !auth_->allowed(ctx))
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED, "missing or invalid bearer token");
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::SubmitJob(grpc::ServerContext* ctx, const v1::SubmitJobRequest* req,
                                          v1::SubmitJobResponse* resp) {
  if (auto st = check_auth(ctx); !st.ok()) return st;
  if (req->idempotency_key().size() > 256)
    return logged("SubmitJob", "", grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                                "idempotency_key: longer than 256 characters ('" +
                                                    echo_text(req->idempotency_key()) + "')"));
  v1::JobSpec spec;
  if (req->has_job()) {
    spec = req->job();
  } else if (req->spec_case() == v1::SubmitJobRequest::kJobJson) {
    auto parsed = job_spec_from_json(req->job_json(), "job_json");
    if (!parsed.ok()) return logged("SubmitJob", "", to_grpc_status(parsed.status()));
    spec = std::move(*parsed);
  } else {
    return logged("SubmitJob", "", grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "job: missing (set job or job_json)"));
  }
  auto submitted = jobs_->submit(req->idempotency_key(), spec);
  if (!submitted.ok()) return logged("SubmitJob", "", to_grpc_status(submitted.status()));
  resp->set_job_id(submitted->job.id());
  resp->set_existing(submitted->existing);
  *resp->mutable_job() = std::move(submitted->job);
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::WatchJob(grpc::ServerContext* ctx, const v1::WatchJobRequest* req,
                                         grpc::ServerWriter<v1::JobEvent>* writer) {
  if (auto st = check_auth(ctx); !st.ok()) return st;
  log_event("info", "watch_started", {{"job", req->job_id()}, {"peer", ctx->peer()}});
  Status st = jobs_->watch(
      *req, [&](const v1::JobEvent& ev) { return writer->Write(ev); }, [&] { return ctx->IsCancelled(); });
  log_event("info", "watch_ended", {{"job", req->job_id()}, {"peer", ctx->peer()}, {"status", st.to_string()}});
  return logged("WatchJob", req->job_id(), to_grpc_status(st));
}

grpc::Status RenderServiceImpl::GetJob(grpc::ServerContext* ctx, const v1::GetJobRequest* req, v1::Job* resp) {
  if (auto st = check_auth(ctx); !st.ok()) return st;
  auto job = jobs_->get(req->job_id());
  if (!job.ok()) return logged("GetJob", req->job_id(), to_grpc_status(job.status()));
  *resp = std::move(*job);
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::ListJobs(grpc::ServerContext* ctx, const v1::ListJobsRequest* req,
                                         v1::ListJobsResponse* resp) {
  if (auto st = check_auth(ctx); !st.ok()) return st;
  auto list = jobs_->list(*req);
  if (!list.ok()) return logged("ListJobs", "", to_grpc_status(list.status()));
  *resp = std::move(*list);
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::CancelJob(grpc::ServerContext* ctx, const v1::CancelJobRequest* req,
                                          v1::Job* resp) {
  if (auto st = check_auth(ctx); !st.ok()) return st;
  auto job = jobs_->cancel(req->job_id());
  if (!job.ok()) return logged("CancelJob", req->job_id(), to_grpc_status(job.status()));
  *resp = std::move(*job);
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::UploadScene(grpc::ServerContext* ctx,
                                            grpc::ServerReader<v1::UploadSceneChunk>* reader,
                                            v1::UploadSceneResponse* resp) {
  if (auto st = check_auth(ctx); !st.ok()) return st;
  // Expired bundles go first, so their room counts for this upload.
  uploads_->sweep(jobs_->uploads_in_use());
  SceneBundleWriter bundle(uploads_, config_.limits.max_upload_bytes);
  v1::UploadSceneChunk chunk;
  while (reader->Read(&chunk)) {
    Status st = bundle.add(chunk.scene_file(), chunk.path(), chunk.data());
    // Returning early ends the call; the client's remaining writes fail fast.
    if (!st.ok()) return logged("UploadScene", "", to_grpc_status(st));
  }
  auto done = bundle.finish();
  if (!done.ok()) return logged("UploadScene", "", to_grpc_status(done.status()));
  resp->set_bundle_hash(done->hash);
  resp->set_scene(done->scene);
  resp->set_total_bytes(done->total_bytes);
  resp->set_files(done->files);
  log_event("info", "scene_uploaded", {{"hash", done->hash}, {"bytes", std::to_string(done->total_bytes)},
                                       {"files", std::to_string(done->files)},
                                       {"upload_folder_bytes", std::to_string(uploads_->used_bytes())},
                                       {"upload_folder_files", std::to_string(uploads_->used_files())}});
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::FetchArtifacts(grpc::ServerContext* ctx, const v1::FetchArtifactsRequest* req,
                                               grpc::ServerWriter<v1::ArtifactChunk>* writer) {
  if (auto st = check_auth(ctx); !st.ok()) return st;
  std::vector<v1::ArtifactKind> kinds;
  for (int k : req->kinds()) {
    if (!v1::ArtifactKind_IsValid(k) || k == v1::ARTIFACT_KIND_UNSPECIFIED)
      return logged("FetchArtifacts", req->job_id(),
                    grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "kinds: unknown kind " + std::to_string(k)));
    kinds.push_back(v1::ArtifactKind(k));
  }
  auto list = jobs_->artifacts(req->job_id(), kinds);
  if (!list.ok()) return logged("FetchArtifacts", req->job_id(), to_grpc_status(list.status()));
  const std::string dir = jobs_->job_dir(req->job_id());
  constexpr size_t kChunk = 1 << 20;  // the API's 1 MiB chunk bound
  std::vector<char> buf(kChunk);
  for (const auto& a : *list) {
    std::ifstream in(dir + "/" + a.file, std::ios::binary | std::ios::ate);
    if (!in) {
      return logged("FetchArtifacts", req->job_id(),
                    grpc::Status(grpc::StatusCode::INTERNAL, "cannot read " + a.file + " on the server"));
    }
    uint64_t total = uint64_t(in.tellg());
    in.seekg(0);
    uint64_t offset = 0;
    do {
      size_t n = size_t(std::min<uint64_t>(kChunk, total - offset));
      in.read(buf.data(), std::streamsize(n));
      if (size_t(in.gcount()) != n)
        return logged("FetchArtifacts", req->job_id(),
                      grpc::Status(grpc::StatusCode::INTERNAL, a.file + " changed while it was sent"));
      v1::ArtifactChunk c;
      c.set_file_name(a.file);
      c.set_kind(a.kind);
      c.set_offset(offset);
      c.set_total_size(total);
      c.set_data(buf.data(), n);
      offset += n;
      c.set_last(offset == total);
      if (!writer->Write(c)) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
    } while (offset < total);
  }
  return grpc::Status::OK;
}

}  // namespace gdvr::server
