#include "client/health_check.h"

#include "grpc/health/v1/health.grpc.pb.h"

namespace gdvr::client {

std::string check_health(const std::shared_ptr<grpc::Channel>& channel, std::chrono::milliseconds deadline,
                         std::string* error) {
  using grpc::health::v1::HealthCheckResponse;
  auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + deadline);
  grpc::health::v1::HealthCheckRequest request;  // service "": the whole server
  HealthCheckResponse response;
  grpc::Status st = stub->Check(&ctx, request, &response);
  if (!st.ok()) {
    *error = st.error_message();
    return "";
  }
  switch (response.status()) {
    case HealthCheckResponse::SERVING: return "SERVING";
    case HealthCheckResponse::NOT_SERVING: return "NOT_SERVING";
    default: return "UNKNOWN";
  }
}

}  // namespace gdvr::client
