#include "server/auth.h"

#include "server/log.h"

namespace gdvr::server {
namespace {

// Compares without an early exit so timing does not reveal a token's prefix.
bool constant_time_equal(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (size_t i = 0; i < a.size(); ++i) diff |= (unsigned char)(a[i] ^ b[i % (b.empty() ? 1 : b.size())]);
  return diff == 0 && !b.empty();
}

class AuthInterceptor : public grpc::experimental::Interceptor {
 public:
  AuthInterceptor(grpc::experimental::ServerRpcInfo* info, std::shared_ptr<TokenAuth> auth)
      : info_(info), auth_(std::move(auth)) {}
  ~AuthInterceptor() override {
    if (rejected_) auth_->forget(info_->server_context());
  }

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    using grpc::experimental::InterceptionHookPoints;
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::POST_RECV_INITIAL_METADATA)) {
      std::string method = info_->method();
      if (auth_->enabled() && !TokenAuth::is_exempt(method)) {
        auto* md = methods->GetRecvInitialMetadata();
        std::string header;
        if (md) {
          auto it = md->find("authorization");
          if (it != md->end()) header.assign(it->second.data(), it->second.size());
        }
        if (!auth_->check_header(header)) {
          rejected_ = true;
          auth_->record_rejected(info_->server_context());
          log_event("warn", "auth_rejected", {{"method", method}, {"reason", header.empty() ? "no token" : "bad token"}});
        }
      }
    }
    if (rejected_ && methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS))
      methods->ModifySendStatus(grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                                             "missing or invalid bearer token (metadata 'authorization: Bearer <token>')"));
    methods->Proceed();
  }

 private:
  grpc::experimental::ServerRpcInfo* info_;
  std::shared_ptr<TokenAuth> auth_;
  bool rejected_ = false;
};

}  // namespace

bool TokenAuth::check_header(const std::string& value) const {
  if (!enabled()) return true;
  const std::string prefix = "Bearer ";
  if (value.size() <= prefix.size() || value.compare(0, prefix.size(), prefix) != 0) return false;
  std::string token = value.substr(prefix.size());
  bool ok = false;
  for (const auto& t : tokens_) ok |= constant_time_equal(token, t);
  return ok;
}

bool TokenAuth::is_exempt(const std::string& method) {
  return method.rfind("/grpc.health.v1.", 0) == 0 || method.rfind("/grpc.reflection.", 0) == 0;
}

void TokenAuth::record_rejected(const grpc::ServerContextBase* ctx) {
  std::lock_guard<std::mutex> lock(mu_);
  rejected_.insert(ctx);
}

void TokenAuth::forget(const grpc::ServerContextBase* ctx) {
  std::lock_guard<std::mutex> lock(mu_);
  rejected_.erase(ctx);
}

bool TokenAuth::allowed(const grpc::ServerContextBase* ctx) const {
  std::lock_guard<std::mutex> lock(mu_);
  return rejected_.count(ctx) == 0;
}

grpc::experimental::Interceptor* AuthInterceptorFactory::CreateServerInterceptor(
    grpc::experimental::ServerRpcInfo* info) {
  return new AuthInterceptor(info, auth_);
}

grpc::Status TokenAuthMetadataProcessor::Process(const InputMetadata& auth_metadata, grpc::AuthContext*,
                                                 OutputMetadata*, OutputMetadata*) {
  auto path = auth_metadata.find(":path");
  std::string method = path == auth_metadata.end() ? "" : std::string(path->second.data(), path->second.size());
  if (TokenAuth::is_exempt(method)) return grpc::Status::OK;
  auto it = auth_metadata.find("authorization");
  std::string header = it == auth_metadata.end() ? "" : std::string(it->second.data(), it->second.size());
  if (!auth_->check_header(header))
    return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                        "missing or invalid bearer token (metadata 'authorization: Bearer <token>')");
  return grpc::Status::OK;
}

}  // namespace gdvr::server
