#include "server/status_map.h"

namespace gdvr::server {

grpc::StatusCode to_grpc_code(gdvr::StatusCode code) {
  switch (code) {
    case gdvr::StatusCode::kOk: return grpc::StatusCode::OK;
    case gdvr::StatusCode::kInvalidArgument: return grpc::StatusCode::INVALID_ARGUMENT;
    case gdvr::StatusCode::kNotFound: return grpc::StatusCode::NOT_FOUND;
    case gdvr::StatusCode::kFailedPrecondition: return grpc::StatusCode::FAILED_PRECONDITION;
    case gdvr::StatusCode::kResourceExhausted: return grpc::StatusCode::RESOURCE_EXHAUSTED;
    case gdvr::StatusCode::kUnimplemented: return grpc::StatusCode::UNIMPLEMENTED;
    case gdvr::StatusCode::kCancelled: return grpc::StatusCode::CANCELLED;
    case gdvr::StatusCode::kInternal: return grpc::StatusCode::INTERNAL;
    case gdvr::StatusCode::kUnavailable: return grpc::StatusCode::UNAVAILABLE;
  }
  return grpc::StatusCode::UNKNOWN;
}

grpc::Status to_grpc_status(const gdvr::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return grpc::Status(to_grpc_code(status.code()), status.message());
}

const char* grpc_code_name(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return "OK";
    case grpc::StatusCode::CANCELLED: return "CANCELLED";
    case grpc::StatusCode::UNKNOWN: return "UNKNOWN";
    case grpc::StatusCode::INVALID_ARGUMENT: return "INVALID_ARGUMENT";
    case grpc::StatusCode::DEADLINE_EXCEEDED: return "DEADLINE_EXCEEDED";
    case grpc::StatusCode::NOT_FOUND: return "NOT_FOUND";
    case grpc::StatusCode::ALREADY_EXISTS: return "ALREADY_EXISTS";
    case grpc::StatusCode::PERMISSION_DENIED: return "PERMISSION_DENIED";
    case grpc::StatusCode::UNAUTHENTICATED: return "UNAUTHENTICATED";
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return "RESOURCE_EXHAUSTED";
    case grpc::StatusCode::FAILED_PRECONDITION: return "FAILED_PRECONDITION";
    case grpc::StatusCode::ABORTED: return "ABORTED";
    case grpc::StatusCode::OUT_OF_RANGE: return "OUT_OF_RANGE";
    case grpc::StatusCode::UNIMPLEMENTED: return "UNIMPLEMENTED";
    case grpc::StatusCode::INTERNAL: return "INTERNAL";
    case grpc::StatusCode::UNAVAILABLE: return "UNAVAILABLE";
    case grpc::StatusCode::DATA_LOSS: return "DATA_LOSS";
    default: return "UNKNOWN";
  }
}

}  // namespace gdvr::server
