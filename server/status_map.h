// The one place where core errors become gRPC statuses (docs/architecture.md).
#pragma once

#include <grpcpp/support/status.h>

#include "core/util/status.h"

namespace gdvr::server {

grpc::StatusCode to_grpc_code(gdvr::StatusCode code);
grpc::Status to_grpc_status(const gdvr::Status& status);
const char* grpc_code_name(grpc::StatusCode code);

}  // namespace gdvr::server
