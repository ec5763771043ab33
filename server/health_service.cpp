#include "server/health_service.h"

#include <chrono>

namespace gdvr::server {

using grpc::health::v1::HealthCheckRequest;
using grpc::health::v1::HealthCheckResponse;

HealthService::HealthService(const std::vector<std::string>& services) {
  for (const auto& s : services) serving_[s] = false;
}

void HealthService::set_serving(bool serving) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (shutdown_) return;
    for (auto& [name, s] : serving_) s = serving;
  }
  cv_.notify_all();
}

void HealthService::shutdown() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    shutdown_ = true;
    for (auto& [name, s] : serving_) s = false;
  }
  cv_.notify_all();
}

HealthService::ServingStatus HealthService::status_locked(const std::string& service) const {
  auto it = serving_.find(service);
  if (it == serving_.end()) return HealthCheckResponse::SERVICE_UNKNOWN;
  return it->second ? HealthCheckResponse::SERVING : HealthCheckResponse::NOT_SERVING;
}

grpc::Status HealthService::Check(grpc::ServerContext*, const HealthCheckRequest* req, HealthCheckResponse* resp) {
  std::lock_guard<std::mutex> lock(mu_);
  ServingStatus s = status_locked(req->service());
  if (s == HealthCheckResponse::SERVICE_UNKNOWN)
    return grpc::Status(grpc::StatusCode::NOT_FOUND, "unknown service name");
  resp->set_status(s);
  return grpc::Status::OK;
}

grpc::Status HealthService::Watch(grpc::ServerContext* ctx, const HealthCheckRequest* req,
                                  grpc::ServerWriter<HealthCheckResponse>* writer) {
  int sent = -1;  // nothing sent yet: the first status goes out at once
  for (;;) {
    ServingStatus now;
    bool ending;
    {
      std::unique_lock<std::mutex> lock(mu_);
      // Woken by a change; the timeout only notices a client that left.
      cv_.wait_for(lock, std::chrono::seconds(1),
                   [&] { return shutdown_ || int(status_locked(req->service())) != sent; });
      now = status_locked(req->service());
      ending = shutdown_;
    }
    if (int(now) != sent) {
      HealthCheckResponse resp;
      resp.set_status(now);
      if (!writer->Write(resp)) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
      sent = int(now);
    }
    if (ending) return grpc::Status(grpc::StatusCode::UNAVAILABLE, "server is shutting down");
    if (ctx->IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "client went away");
  }
}

}  // namespace gdvr::server
