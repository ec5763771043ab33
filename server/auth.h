// Bearer-token authentication. On plaintext an interceptor checks the
// `authorization: Bearer <token>` metadata of every call; with TLS an
// AuthMetadataProcessor rejects bad calls before they reach a handler.
//
// gRPC C++ server interceptors cannot fail a call themselves (grpc/grpc#22395,
// #24017), so the interceptor records its verdict per call and also rewrites
// the final status to UNAUTHENTICATED; RenderService handlers consult the
// verdict first (TokenAuth::allowed) so no work is done for a rejected call.
#pragma once

#include <grpcpp/grpcpp.h>
#include <grpcpp/security/auth_metadata_processor.h>
#include <grpcpp/support/server_interceptor.h>

#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace gdvr::server {

class TokenAuth {
 public:
  explicit TokenAuth(std::vector<std::string> tokens) : tokens_(std::move(tokens)) {}
  bool enabled() const { return !tokens_.empty(); }
  // Checks an `authorization` header value ("Bearer <token>").
  bool check_header(const std::string& value) const;
  // Health checks and reflection stay open so probes and tools work without a token.
  static bool is_exempt(const std::string& method);

  void record_rejected(const grpc::ServerContextBase* ctx);
  void forget(const grpc::ServerContextBase* ctx);
  // False when the interceptor rejected this call.
  bool allowed(const grpc::ServerContextBase* ctx) const;

 private:
  std::vector<std::string> tokens_;
  mutable std::mutex mu_;
  std::set<const grpc::ServerContextBase*> rejected_;
};

class AuthInterceptorFactory : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit AuthInterceptorFactory(std::shared_ptr<TokenAuth> auth) : auth_(std::move(auth)) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(grpc::experimental::ServerRpcInfo* info) override;

 private:
  std::shared_ptr<TokenAuth> auth_;
};

class TokenAuthMetadataProcessor : public grpc::AuthMetadataProcessor {
 public:
  explicit TokenAuthMetadataProcessor(std::shared_ptr<TokenAuth> auth) : auth_(std::move(auth)) {}
  bool IsBlocking() const override { return false; }
  grpc::Status Process(const InputMetadata& auth_metadata, grpc::AuthContext* context,
                       OutputMetadata* consumed_auth_metadata, OutputMetadata* response_metadata) override;

 private:
  std::shared_ptr<TokenAuth> auth_;
};

}  // namespace gdvr::server
