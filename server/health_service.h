// grpc.health.v1.Health for gdvr-server (proto/grpc/health/v1/health.proto).
// gRPC 1.51's built-in health service never ends a Watch stream, so one open
// Watch (Kubernetes and Envoy hold them) kept the server from exiting for the
// whole shutdown grace period. Here shutdown() sends NOT_SERVING to every
// watcher and then ends its stream, and the rest of shutdown is prompt.
#pragma once

#include <grpcpp/grpcpp.h>

#include <condition_variable>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "grpc/health/v1/health.grpc.pb.h"

namespace gdvr::server {

class HealthService final : public grpc::health::v1::Health::Service {
 public:
  // The names Check and Watch know ("" is the whole server); all NOT_SERVING
  // until set_serving(true). Other names: Check is NOT_FOUND, Watch sends
  // SERVICE_UNKNOWN (the protocol's rules).
  explicit HealthService(const std::vector<std::string>& services);

  void set_serving(bool serving);
  // Every name NOT_SERVING for good; each Watch stream gets that status and
  // then ends with UNAVAILABLE ("shutting down"), so no stream holds the
  // server's shutdown.
  void shutdown();

  grpc::Status Check(grpc::ServerContext* ctx, const grpc::health::v1::HealthCheckRequest* req,
                     grpc::health::v1::HealthCheckResponse* resp) override;
  grpc::Status Watch(grpc::ServerContext* ctx, const grpc::health::v1::HealthCheckRequest* req,
                     grpc::ServerWriter<grpc::health::v1::HealthCheckResponse>* writer) override;

 private:
  using ServingStatus = grpc::health::v1::HealthCheckResponse::ServingStatus;
  ServingStatus status_locked(const std::string& service) const;

  std::mutex mu_;
  std::condition_variable cv_;
  std::map<std::string, bool> serving_;
  bool shutdown_ = false;
};

}  // namespace gdvr::server
