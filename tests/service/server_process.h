// Starts the real gdvr-server binary on an ephemeral localhost port for
// integration tests, in its own temporary folder (assets, outputs, db).
#pragma once

#include <grpcpp/grpcpp.h>
#include <sys/types.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "gdvr/v1/render_service.grpc.pb.h"

namespace gdvr::testing {

// A temporary folder with a copy of scenes/cbox under assets/ (a copy, not a
// symlink: the server resolves symlinks and would see it outside its root).
class TestDir {
 public:
  TestDir();
  ~TestDir();
  const std::string& path() const { return path_; }
  std::string assets() const { return path_ + "/assets"; }
  std::string out() const { return path_ + "/out"; }

 private:
  std::string path_;
};

class ServerProcess {
 public:
  ServerProcess(const TestDir& dir, std::vector<std::string> extra_args = {},
                std::map<std::string, std::string> env = {});
  ~ServerProcess();  // SIGKILL if still running

  // Connect over TLS trusting `ca_pem` (PEM text) from then on, e.g. for a
  // server started with --tls-cert/--tls-key.
  void use_tls(std::string ca_pem) { tls_ca_ = std::move(ca_pem); }

  bool start();       // waits until the port file appears and health answers
  void kill9();
  int terminate();    // SIGTERM; returns the exit status (-1 on timeout)
  bool running() const { return pid_ > 0; }
  std::string address() const { return "127.0.0.1:" + std::to_string(port_); }
  std::shared_ptr<grpc::Channel> channel() const;
  std::unique_ptr<v1::RenderService::Stub> stub() const { return v1::RenderService::NewStub(channel()); }
  const std::string& log_path() const { return log_; }

 private:
  const TestDir& dir_;
  std::vector<std::string> args_;
  std::map<std::string, std::string> env_;
  pid_t pid_ = -1;
  int port_ = 0;
  std::string log_;
  std::string tls_ca_;
};

// grpc.health.v1 Check for the overall server ("" service).
std::string health_status(const std::shared_ptr<grpc::Channel>& channel);

}  // namespace gdvr::testing
