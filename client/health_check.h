// grpc.health.v1.Health/Check for the whole server (service ""): what
// `gdvr health` and the service tests wait on.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

namespace gdvr::client {

// "SERVING", "NOT_SERVING" or "UNKNOWN"; "" with `*error` set when the call
// itself fails (unreachable, deadline, TLS).
std::string check_health(const std::shared_ptr<grpc::Channel>& channel, std::chrono::milliseconds deadline,
                         std::string* error);

}  // namespace gdvr::client
