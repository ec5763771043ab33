// Channel set-up shared by the gdvr CLI verbs: address, bearer token, TLS,
// and the mapping of call failures to clear messages and exit codes.
#pragma once

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

#include "gdvr/v1/render_service.grpc.pb.h"

namespace gdvr::client {

struct ConnectionOptions {
  std::string server = "127.0.0.1:50051";
  std::string token;                     // bearer token; empty: none
  std::string tls_ca, tls_cert, tls_key; // TLS when tls_ca is set; mTLS with cert+key
};

// Exit codes of the gdvr CLI (documented in `gdvr --help`).
enum ExitCode {
  kExitOk = 0,
  kExitJobFailed = 1,   // the job failed or was cancelled
  kExitUsage = 2,
  kExitUnreachable = 3, // server down, wrong address, TLS mismatch
  kExitAuth = 4,        // missing or wrong token
  kExitRejected = 5,    // invalid job or request (the message names the field)
  kExitError = 6,       // anything else (I/O, internal)
};

class Connection {
 public:
  explicit Connection(ConnectionOptions options);
  v1::RenderService::Stub* stub() { return stub_.get(); }
  // A context carrying the token; `deadline_s` 0: none (streams).
  std::unique_ptr<grpc::ClientContext> context(double deadline_s = 30) const;
  const ConnectionOptions& options() const { return options_; }

 private:
  ConnectionOptions options_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::RenderService::Stub> stub_;
};

// Prints "gdvr: <what>: <explanation>" to stderr and returns the exit code.
int report_rpc_error(const std::string& what, const grpc::Status& status, const ConnectionOptions& options);

}  // namespace gdvr::client
