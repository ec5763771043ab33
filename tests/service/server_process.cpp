#include "tests/service/server_process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "client/health_check.h"

namespace gdvr::testing {
namespace fs = std::filesystem;

TestDir::TestDir() {
  char tmpl[] = "/tmp/gdvr-svc-test-XXXXXX";
  path_ = mkdtemp(tmpl);
  fs::create_directories(assets());
  fs::copy(std::string(GDVR_SOURCE_DIR) + "/scenes/cbox", assets() + "/cbox", fs::copy_options::recursive);
}

TestDir::~TestDir() {
  if (!std::getenv("GDVR_KEEP_TEST_DIRS")) {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
}

ServerProcess::ServerProcess(const TestDir& dir, std::vector<std::string> extra_args,
                             std::map<std::string, std::string> env)
    : dir_(dir), args_(std::move(extra_args)), env_(std::move(env)) {}

ServerProcess::~ServerProcess() {
  if (pid_ > 0) kill9();
}

bool ServerProcess::start() {
  std::string port_file = dir_.path() + "/port";
  fs::remove(port_file);
  log_ = dir_.path() + "/server.log";
  std::vector<std::string> argv = {GDVR_SERVER_BIN,        "--listen=127.0.0.1:0", "--port-file=" + port_file,
                                   "--asset-root=" + dir_.assets(), "--output-root=" + dir_.out(),
                                   "--threads=2"};
  argv.insert(argv.end(), args_.begin(), args_.end());
  pid_ = fork();
  if (pid_ == 0) {
    int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    for (const auto& [k, v] : env_) setenv(k.c_str(), v.c_str(), 1);
    std::vector<char*> cargv;
    for (auto& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    execv(cargv[0], cargv.data());
    _exit(127);
  }
  for (int i = 0; i < 400; ++i) {
    std::ifstream in(port_file);
    if (in >> port_ && port_ > 0) return health_status(channel()) == "SERVING";
    int status;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

void ServerProcess::kill9() {
  if (pid_ <= 0) return;
  ::kill(pid_, SIGKILL);
  int status;
  waitpid(pid_, &status, 0);
  pid_ = -1;
}

int ServerProcess::terminate() {
  if (pid_ <= 0) return -1;
  ::kill(pid_, SIGTERM);
  for (int i = 0; i < 300; ++i) {
    int status;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return -1;
}

std::shared_ptr<grpc::Channel> ServerProcess::channel() const {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(16 << 20);
  if (tls_ca_.empty()) return grpc::CreateCustomChannel(address(), grpc::InsecureChannelCredentials(), args);
  grpc::SslCredentialsOptions ssl;
  ssl.pem_root_certs = tls_ca_;
  return grpc::CreateCustomChannel(address(), grpc::SslCredentials(ssl), args);
}

std::string health_status(const std::shared_ptr<grpc::Channel>& channel) {
  std::string error;
  const std::string status = client::check_health(channel, std::chrono::seconds(5), &error);
  return status.empty() ? "ERROR:" + error : status;
}

}  // namespace gdvr::testing
