// gdvr.v1.RenderService: thin adapters from proto requests to JobManager.
#pragma once

#include <memory>

#include "gdvr/v1/render_service.grpc.pb.h"
#include "server/auth.h"
#include "server/config.h"
#include "server/job_manager.h"
#include "server/upload_store.h"

namespace gdvr::server {

class RenderServiceImpl final : public v1::RenderService::Service {
 public:
  RenderServiceImpl(JobManager* jobs, UploadStore* uploads, std::shared_ptr<TokenAuth> auth,
                    const ServerConfig& config)
      : jobs_(jobs), uploads_(uploads), auth_(std::move(auth)), config_(config) {}

  grpc::Status SubmitJob(grpc::ServerContext* ctx, const v1::SubmitJobRequest* req,
                         v1::SubmitJobResponse* resp) override;
  grpc::Status WatchJob(grpc::ServerContext* ctx, const v1::WatchJobRequest* req,
                        grpc::ServerWriter<v1::JobEvent>* writer) override;
  grpc::Status GetJob(grpc::ServerContext* ctx, const v1::GetJobRequest* req, v1::Job* resp) override;
  grpc::Status ListJobs(grpc::ServerContext* ctx, const v1::ListJobsRequest* req,
                        v1::ListJobsResponse* resp) override;
  grpc::Status CancelJob(grpc::ServerContext* ctx, const v1::CancelJobRequest* req, v1::Job* resp) override;
  grpc::Status UploadScene(grpc::ServerContext* ctx, grpc::ServerReader<v1::UploadSceneChunk>* reader,
                           v1::UploadSceneResponse* resp) override;
  grpc::Status FetchArtifacts(grpc::ServerContext* ctx, const v1::FetchArtifactsRequest* req,
                              grpc::ServerWriter<v1::ArtifactChunk>* writer) override;

 private:
  grpc::Status check_auth(grpc::ServerContext* ctx) const;
  // Logs a failed call and returns what the client is shown of it.
  grpc::Status logged(const char* rpc, const std::string& job, const grpc::Status& st) const;

  JobManager* jobs_;
  UploadStore* uploads_;
  std::shared_ptr<TokenAuth> auth_;
  const ServerConfig& config_;
};

}  // namespace gdvr::server
