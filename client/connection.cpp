#include "client/connection.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace gdvr::client {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

Connection::Connection(ConnectionOptions options) : options_(std::move(options)) {
  std::shared_ptr<grpc::ChannelCredentials> creds;
  if (!options_.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    ssl.pem_root_certs = read_text(options_.tls_ca);
    if (!options_.tls_cert.empty()) {
      ssl.pem_cert_chain = read_text(options_.tls_cert);
      ssl.pem_private_key = read_text(options_.tls_key);
    }
    creds = grpc::SslCredentials(ssl);
  } else {
    creds = grpc::InsecureChannelCredentials();
  }
  grpc::ChannelArguments args;
  // Long, quiet watch streams: ping so idle connections are not dropped.
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 30000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20000);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  args.SetMaxReceiveMessageSize(16 << 20);
  channel_ = grpc::CreateCustomChannel(options_.server, creds, args);
  stub_ = v1::RenderService::NewStub(channel_);
}

std::unique_ptr<grpc::ClientContext> Connection::context(double deadline_s) const {
  auto ctx = std::make_unique<grpc::ClientContext>();
  if (!options_.token.empty()) ctx->AddMetadata("authorization", "Bearer " + options_.token);
  if (deadline_s > 0)
    ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(int64_t(deadline_s * 1000)));
  return ctx;
}

int report_rpc_error(const std::string& what, const grpc::Status& st, const ConnectionOptions& options) {
  const std::string& msg = st.error_message();
  switch (st.error_code()) {
    case grpc::StatusCode::UNAVAILABLE:
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      std::fprintf(stderr, "gdvr: %s: cannot reach gdvr-server at %s (%s). Is it running? Check --server.\n",
                   what.c_str(), options.server.c_str(), msg.c_str());
      return kExitUnreachable;
    case grpc::StatusCode::UNAUTHENTICATED:
    case grpc::StatusCode::PERMISSION_DENIED:
      std::fprintf(stderr, "gdvr: %s: authentication failed (%s). Pass --token or set GDVR_TOKEN.\n", what.c_str(),
                   msg.c_str());
      return kExitAuth;
    case grpc::StatusCode::INVALID_ARGUMENT:
    case grpc::StatusCode::NOT_FOUND:
    case grpc::StatusCode::FAILED_PRECONDITION:
    case grpc::StatusCode::RESOURCE_EXHAUSTED:
    case grpc::StatusCode::ALREADY_EXISTS:
    case grpc::StatusCode::OUT_OF_RANGE:
      std::fprintf(stderr, "gdvr: %s: rejected: %s\n", what.c_str(), msg.c_str());
      return kExitRejected;
    default:
      std::fprintf(stderr, "gdvr: %s: error %d: %s\n", what.c_str(), int(st.error_code()), msg.c_str());
      return kExitError;
  }
}

}  // namespace gdvr::client
