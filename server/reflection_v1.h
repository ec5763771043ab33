// grpc.reflection.v1.ServerReflection (proto/grpc/reflection/v1), served next
// to gRPC 1.51's v1alpha plugin, which has no v1. Answers from the protobuf
// generated pool, as the v1alpha plugin does: every service the server
// registers is compiled into the binary.
#pragma once

#include <grpcpp/grpcpp.h>

#include <string>
#include <vector>

#include "grpc/reflection/v1/reflection.grpc.pb.h"

namespace gdvr::server {

class ReflectionV1Service final : public grpc::reflection::v1::ServerReflection::Service {
 public:
  // The fully qualified names ListServices returns.
  explicit ReflectionV1Service(std::vector<std::string> services) : services_(std::move(services)) {}

  grpc::Status ServerReflectionInfo(
      grpc::ServerContext* ctx,
      grpc::ServerReaderWriter<grpc::reflection::v1::ServerReflectionResponse,
                               grpc::reflection::v1::ServerReflectionRequest>* stream) override;

 private:
  std::vector<std::string> services_;
};

}  // namespace gdvr::server
