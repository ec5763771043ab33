// gdvr-bench-stream: what streaming costs.
//   1. Overhead: a job's render time (server-side, started -> finished) with N
//      clients watching it (default 8), divided by its time with none. Runs
//      alternate (none, N, none, N, ...) so drifting machine load hits both
//      sides alike; the ratio is of the medians. Target <= 1.02.
//   2. Latency: from a frame becoming final on the server (persisted and
//      announced; FrameFinal.final_unix_us) to its last chunk arriving at a
//      localhost client, for a 1280x720 frame. Target median <= 50 ms. Server
//      and client share the clock, so the difference is meaningful.
// Starts its own gdvr-server on an ephemeral port in a temporary folder.
#include <grpcpp/grpcpp.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "core/util/cli_args.h"
#include "gdvr/v1/render_service.grpc.pb.h"

namespace fs = std::filesystem;
namespace v1 = gdvr::v1;

namespace {

const char* kUsage = R"(usage: gdvr-bench-stream [flags]
  --server-bin PATH     gdvr-server to start (default: the one built beside this tool)
  --asset-root DIR      default: the repository's scenes/
  --runs N              runs per configuration (default 3; medians are reported)
  --watchers N          clients watching in the loaded runs (default 8)
  --threads N           render threads of the server (default 0: all cores)
  --overhead-job JSON   job for the overhead runs
  --latency-job JSON    job for the latency runs (1280x720)
  --skip-overhead | --skip-latency
)";

int64_t now_us() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(p * double(v.size() - 1) + 0.5))];
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

// CPU seconds (user + system) a process has used so far.
double cpu_seconds(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), {});
  size_t p = text.rfind(')');  // the command name may hold spaces
  if (p == std::string::npos) return 0;
  std::istringstream ss(text.substr(p + 2));
  std::string field;
  unsigned long long utime = 0, stime = 0;
  for (int i = 3; i <= 15 && ss >> field; ++i) {
    if (i == 14) utime = std::stoull(field);
    if (i == 15) stime = std::stoull(field);
  }
  return double(utime + stime) / double(sysconf(_SC_CLK_TCK));
}

struct Server {
  pid_t pid = -1;
  std::string address, dir;

  bool start(const std::string& bin, const std::string& assets, int threads) {
    char tmpl[] = "/tmp/gdvr-bench-stream-XXXXXX";
    dir = mkdtemp(tmpl);
    std::string port_file = dir + "/port";
    std::vector<std::string> args = {bin, "--listen=127.0.0.1:0", "--port-file=" + port_file,
                                     "--asset-root=" + assets, "--output-root=" + dir + "/out",
                                     "--threads=" + std::to_string(threads)};
    pid = fork();
    if (pid == 0) {
      // Its own session, hence its own scheduler autogroup: otherwise the
      // server's CPU share on a shared machine would grow with the activity of
      // this process's watcher threads, and the runs with watchers would look
      // faster than those without.
      setsid();
      FILE* log = std::freopen((dir + "/server.log").c_str(), "w", stdout);
      (void)log;
      dup2(STDOUT_FILENO, STDERR_FILENO);
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    for (int i = 0; i < 600; ++i) {
      std::ifstream in(port_file);
      int port = 0;
      if (in >> port && port > 0) {
        address = "127.0.0.1:" + std::to_string(port);
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }
  void stop() {
    if (pid <= 0) return;
    kill(pid, SIGTERM);
    int status;
    waitpid(pid, &status, 0);
    pid = -1;
    std::error_code ec;
    if (!std::getenv("GDVR_KEEP_TEST_DIRS")) fs::remove_all(dir, ec);
  }
};

std::shared_ptr<grpc::Channel> new_channel(const std::string& address) {
  // A distinct channel argument forces a separate connection per client, as
  // separate processes would have.
  static std::atomic<int> n{0};
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(16 << 20);
  args.SetInt("gdvr.bench.client", n++);
  return grpc::CreateCustomChannel(address, grpc::InsecureChannelCredentials(), args);
}

std::string submit(const std::string& address, const std::string& key, const std::string& json) {
  auto stub = v1::RenderService::NewStub(new_channel(address));
  grpc::ClientContext ctx;
  v1::SubmitJobRequest req;
  req.set_idempotency_key(key);
  req.set_job_json(json);
  v1::SubmitJobResponse resp;
  grpc::Status st = stub->SubmitJob(&ctx, req, &resp);
  if (!st.ok()) {
    std::fprintf(stderr, "gdvr-bench-stream: submit failed: %s\n", st.error_message().c_str());
    std::exit(1);
  }
  return resp.job_id();
}

v1::Job wait_done(const std::string& address, const std::string& id) {
  auto stub = v1::RenderService::NewStub(new_channel(address));
  for (;;) {
    grpc::ClientContext ctx;
    v1::GetJobRequest req;
    req.set_job_id(id);
    v1::Job job;
    grpc::Status st = stub->GetJob(&ctx, req, &job);
    if (st.ok() && job.state() >= v1::JOB_STATE_COMPLETED) {
      if (job.state() != v1::JOB_STATE_COMPLETED) {
        std::fprintf(stderr, "gdvr-bench-stream: job %s did not complete: %s\n", id.c_str(), job.reason().c_str());
        std::exit(1);
      }
      return job;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
}

// One watching client: reads every event; records, per frame, the latency of
// its last chunk. Returns the number of complete frames seen.
int watch(const std::string& address, const std::string& id, std::vector<double>* latencies_ms) {
  auto stub = v1::RenderService::NewStub(new_channel(address));
  grpc::ClientContext ctx;
  v1::WatchJobRequest req;
  req.set_job_id(id);
  auto reader = stub->WatchJob(&ctx, req);
  v1::JobEvent ev;
  int frames = 0;
  while (reader->Read(&ev)) {
    if (ev.has_frame_final() && ev.frame_final().last()) {
      int64_t arrived = now_us();
      ++frames;
      if (latencies_ms && ev.frame_final().final_unix_us() > 0)
        latencies_ms->push_back(double(arrived - ev.frame_final().final_unix_us()) / 1000.0);
    }
  }
  (void)reader->Finish();
  return frames;
}

struct RunTime {
  double wall_s = 0;        // server-side, started -> finished
  double server_cpu_s = 0;  // CPU the server process used meanwhile
};

// Runs the job once with `watchers` clients.
RunTime run_once(const Server& server, const std::string& json, int watchers, int run,
                 std::vector<double>* latencies_ms = nullptr) {
  const std::string& address = server.address;
  double cpu0 = cpu_seconds(server.pid);
  std::string id = submit(address, "bench-" + std::to_string(run) + "-" + std::to_string(watchers) + "-" +
                                       std::to_string(now_us()), json);
  std::vector<std::thread> threads;
  std::vector<std::vector<double>> lat(size_t(std::max(watchers, 0)));
  for (int w = 0; w < watchers; ++w)
    threads.emplace_back([&, w] { watch(address, id, &lat[size_t(w)]); });
  v1::Job job = wait_done(address, id);
  for (auto& t : threads) t.join();
  if (latencies_ms)
    for (auto& l : lat) latencies_ms->insert(latencies_ms->end(), l.begin(), l.end());
  return {double(job.finished_unix_ms() - job.started_unix_ms()) / 1000.0, cpu_seconds(server.pid) - cpu0};
}

}  // namespace

int main(int argc, char** argv) {
  signal(SIGPIPE, SIG_IGN);
  std::string server_bin = fs::path(fs::read_symlink("/proc/self/exe")).parent_path() / "gdvr-server";
  std::string assets = std::string(GDVR_SOURCE_DIR) + "/scenes";
  int runs = 3, watchers = 8, threads = 0;
  bool overhead = true, latency = true;
  std::string overhead_job =
      R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-4", "width": 256, "height": 256, "spp": 16, "seed": 1})";
  std::string latency_job =
      R"({"scene": "cbox/cbox-rgb.xml", "frames": "1-8", "width": 1280, "height": 720, "spp": 1, "seed": 1})";
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n%s", a.c_str(), kUsage);
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--server-bin") server_bin = next();
    else if (a == "--asset-root") assets = next();
    else if (a == "--runs") runs = int(gdvr::tools::int_option("gdvr-bench-stream", a, next(), 1, 1000));
    else if (a == "--watchers") watchers = int(gdvr::tools::int_option("gdvr-bench-stream", a, next(), 1, 1000));
    else if (a == "--threads") threads = int(gdvr::tools::int_option("gdvr-bench-stream", a, next(), 0, 1024));
    else if (a == "--overhead-job") overhead_job = next();
    else if (a == "--latency-job") latency_job = next();
    else if (a == "--skip-overhead") overhead = false;
    else if (a == "--skip-latency") latency = false;
    else {
      std::fputs(kUsage, a == "--help" || a == "-h" ? stdout : stderr);
      return a == "--help" || a == "-h" ? 0 : 2;
    }
  }
  Server server;
  if (!server.start(server_bin, assets, threads)) {
    std::fprintf(stderr, "gdvr-bench-stream: cannot start %s (log in %s)\n", server_bin.c_str(), server.dir.c_str());
    server.stop();
    return 1;
  }
  std::printf("gdvr-bench-stream: server %s, %u hardware threads, load average %s\n", server.address.c_str(),
              std::thread::hardware_concurrency(), load_average().c_str());
  std::fflush(stdout);
  // Warm-up: scene parse caches, page cache, first-connection costs.
  (void)run_once(server,
                 R"({"scene": "cbox/cbox-rgb.xml", "frames": "1", "width": 32, "height": 32, "spp": 1})", 1, -1);

  if (overhead) {
    std::vector<double> none, loaded, cpu_none, cpu_loaded;
    for (int r = 0; r < runs; ++r) {
      RunTime a = run_once(server, overhead_job, 0, r);
      RunTime b = run_once(server, overhead_job, watchers, r);
      none.push_back(a.wall_s), cpu_none.push_back(a.server_cpu_s);
      loaded.push_back(b.wall_s), cpu_loaded.push_back(b.server_cpu_s);
      std::printf("  run %d: %.3f s (server CPU %.3f s) with no watcher, %.3f s (CPU %.3f s) with %d (load %s)\n",
                  r + 1, a.wall_s, a.server_cpu_s, b.wall_s, b.server_cpu_s, watchers, load_average().c_str());
      std::fflush(stdout);
    }
    double m0 = median(none), m1 = median(loaded);
    // Adjacent runs see similar neighbour load: the median of per-pair ratios
    // is the steadier estimate on a shared machine.
    std::vector<double> pair_ratios;
    for (size_t i = 0; i < none.size(); ++i) pair_ratios.push_back(loaded[i] / none[i]);
    std::printf("overhead: job %s\n  render time: median %.3f s with no watcher, %.3f s with %d; ratio %.4f "
                "(target <= 1.02); median of per-pair ratios %.4f\n",
                overhead_job.c_str(), m0, m1, watchers, m1 / m0, median(pair_ratios));
    // Wall time on a shared machine follows the neighbours' load; the server's
    // CPU time is what streaming costs regardless of them.
    double c0 = median(cpu_none), c1 = median(cpu_loaded);
    std::printf("  server CPU: median %.3f s with no watcher, %.3f s with %d; ratio %.4f\n", c0, c1, watchers,
                c1 / c0);
    std::fflush(stdout);
  }
  if (latency) {
    std::vector<double> one, many;
    for (int r = 0; r < runs; ++r) {
      (void)run_once(server, latency_job, 1, 100 + r, &one);
      (void)run_once(server, latency_job, watchers, 200 + r, &many);
      std::printf("  run %d done (load %s)\n", r + 1, load_average().c_str());
      std::fflush(stdout);
    }
    std::printf("latency (frame final on the server -> last chunk at the client): job %s\n", latency_job.c_str());
    std::printf("  1 client:   median %.1f ms, p90 %.1f ms, max %.1f ms over %zu frames (target median <= 50)\n",
                median(one), percentile(one, 0.9), percentile(one, 1.0), one.size());
    std::printf("  %d clients: median %.1f ms, p90 %.1f ms, max %.1f ms over %zu frame deliveries\n", watchers,
                median(many), percentile(many, 0.9), percentile(many, 1.0), many.size());
  }
  std::printf("load average at the end: %s\n", load_average().c_str());
  server.stop();
  return 0;
}
