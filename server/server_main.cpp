// gdvr-server: the long-running render service. Wiring only: flags, store,
// job manager, gRPC server (health, reflection, auth), signals.
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "core/util/path_confinement.h"
#include "server/auth.h"
#include "server/call_tracker.h"
#include "core/denoise/oidn_denoiser.h"
#include "server/config.h"
#include "server/health_service.h"
#include "server/job_manager.h"
#include "server/job_store.h"
#include "server/log.h"
#include "server/reflection_v1.h"
#include "server/render_service.h"
#include "server/upload_store.h"

namespace fs = std::filesystem;
using namespace gdvr::server;

namespace {

bool read_pem(const std::string& path, std::string* out) {
  std::ifstream in(path);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return true;
}

int fail(const std::string& msg) {
  log_event("error", "startup_failed", {{"error", msg}});
  std::fprintf(stderr, "gdvr-server: %s\n", msg.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  // A client vanishing mid-write must not kill the server.
  signal(SIGPIPE, SIG_IGN);
  // Block the stop signals before any thread exists so every thread inherits
  // the mask and only sigwait() below receives them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  auto parsed = parse_server_flags(argc, argv);
  if (!parsed.ok()) {
    if (parsed.status().code() == gdvr::StatusCode::kFailedPrecondition) {
      std::fputs(parsed.status().message().c_str(), stdout);
      return 0;
    }
    return fail(parsed.status().message());
  }
  ServerConfig config = std::move(*parsed);
  {
    std::string why;
    config.denoiser = gdvr::make_job_denoiser(config.threads, &why);
    if (config.denoiser) log_event("info", "denoiser", {{"name", "Intel Open Image Denoise"}, {"use", "tgpt data term"}});
    else log_event("info", "no_denoiser", {{"why", why}, {"effect", "tgpt's data term is the sampled primal"}});
  }
  std::error_code ec;
  if (!fs::is_directory(config.asset_root, ec)) return fail("--asset-root: '" + config.asset_root + "' is not a folder");
  fs::create_directories(config.output_root, ec);
  if (ec) return fail("--output-root: cannot create '" + config.output_root + "': " + ec.message());

  // Uploads are kept out of the operator's asset root: a bundle must not
  // become an asset other jobs can name, nor fill the operator's folder.
  if (gdvr::is_inside_root(config.uploads.root, config.asset_root))
    log_event("warn", "upload_root_inside_asset_root",
              {{"upload_root", config.uploads.root}, {"asset_root", config.asset_root},
               {"hint", "set --upload-root (or --output-root) outside --asset-root"}});
  UploadStore uploads(config.uploads);
  if (auto st = uploads.open(); !st.ok()) return fail(st.message());

  auto store = JobStore::open(config.db_path);
  if (!store.ok()) return fail(store.status().message());
  JobManager jobs(config, std::move(*store), &uploads);
  if (auto st = jobs.recover(); !st.ok()) return fail(st.message());
  uploads.sweep(jobs.uploads_in_use());

  auto auth = std::make_shared<TokenAuth>(config.tokens);
  RenderServiceImpl service(&jobs, &uploads, auth, config);
  // Our own health service (see health_service.h); the service name is
  // registered too, for probes that ask about gdvr.v1.RenderService.
  const std::string kServiceName = gdvr::v1::RenderService::service_full_name();
  HealthService health({"", kServiceName});
  ReflectionV1Service reflection_v1({kServiceName, "grpc.health.v1.Health", "grpc.reflection.v1.ServerReflection",
                                     "grpc.reflection.v1alpha.ServerReflection"});

  grpc::reflection::InitProtoReflectionServerBuilderPlugin();  // v1alpha
  grpc::ServerBuilder builder;

  std::shared_ptr<grpc::ServerCredentials> creds;
  if (!config.tls_cert.empty()) {
    grpc::SslServerCredentialsOptions ssl;
    grpc::SslServerCredentialsOptions::PemKeyCertPair pair;
    if (!read_pem(config.tls_key, &pair.private_key)) return fail("--tls-key: cannot read '" + config.tls_key + "'");
    if (!read_pem(config.tls_cert, &pair.cert_chain)) return fail("--tls-cert: cannot read '" + config.tls_cert + "'");
    ssl.pem_key_cert_pairs.push_back(pair);
    if (!config.tls_ca.empty()) {
      if (!read_pem(config.tls_ca, &ssl.pem_root_certs)) return fail("--tls-ca: cannot read '" + config.tls_ca + "'");
      ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
    }
    creds = grpc::SslServerCredentials(ssl);
    if (auth->enabled()) creds->SetAuthMetadataProcessor(std::make_shared<TokenAuthMetadataProcessor>(auth));
  } else {
    creds = grpc::InsecureServerCredentials();
  }
  int port = 0;
  builder.AddListeningPort(config.listen, creds, &port);
  builder.RegisterService(&service);
  builder.RegisterService(&health);
  builder.RegisterService(&reflection_v1);
  builder.SetMaxReceiveMessageSize(config.limits.max_message_bytes);
  builder.SetMaxSendMessageSize(std::max(config.limits.max_message_bytes, 4 << 20));
  // Watch streams can be quiet for minutes while a frame renders: ping so
  // NATs and proxies keep the connection, and let clients ping us too.
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, config.keepalive_time_s * 1000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10000);
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  CallTracker calls;
  interceptors.push_back(calls.interceptor_factory());
  if (auth->enabled()) interceptors.push_back(std::make_unique<AuthInterceptorFactory>(auth));
  builder.experimental().SetInterceptorCreators(std::move(interceptors));

  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (!server || port == 0) return fail("--listen: cannot listen on '" + config.listen + "'");
  health.set_serving(true);
  jobs.start();
  if (!config.port_file.empty()) {
    // Write then rename: a test polling for the file never reads half a port.
    std::string tmp = config.port_file + ".tmp";
    std::ofstream(tmp) << port << "\n";
    fs::rename(tmp, config.port_file, ec);
  }
  log_event("info", "serving", {{"listen", config.listen}, {"port", std::to_string(port)},
                                {"tls", config.tls_cert.empty() ? "off" : (config.tls_ca.empty() ? "on" : "mtls")},
                                {"auth", auth->enabled() ? "bearer" : "off"}, {"asset_root", config.asset_root},
                                {"output_root", config.output_root}, {"db", config.db_path},
                                {"concurrency", std::to_string(config.concurrency)}});

  int sig = 0;
  sigwait(&stop_signals, &sig);
  log_event("info", "shutdown_begin", {{"signal", sig == SIGTERM ? "SIGTERM" : "SIGINT"}});
  // ---- Graceful shutdown ----
  // Probes see NOT_SERVING first, so load balancers drain us; open health
  // Watch streams get it and then end, so they do not hold the shutdown.
  health.shutdown();
  // Stops new work, cancels running renders (their final frames are already
  // persisted; the job stays queued for the next start) and ends watch streams.
  jobs.shutdown();
  auto deadline = std::chrono::system_clock::now() +
                  std::chrono::milliseconds(int64_t(config.shutdown_grace_s * 1000));
  // Calls still in flight (a download, a submit) get until the deadline. Once
  // none is left, connections are closed at once instead of waiting for
  // idle clients to answer the graceful GOAWAY (see call_tracker.h).
  std::atomic<bool> shut_down{false};
  std::thread closer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // let Shutdown() begin
    while (!shut_down && calls.active() > 0 && std::chrono::system_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (!shut_down) grpc_server_cancel_all_calls(server->c_server());
  });
  server->Shutdown(deadline);
  shut_down = true;
  closer.join();
  server->Wait();
  log_event("info", "shutdown_done");
  return 0;
}
