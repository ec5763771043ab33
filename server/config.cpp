#include "server/config.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace gdvr::server {
namespace {

std::string trim(const std::string& s) {
  size_t b = s.find_first_not_of(" \t\r\n"), e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

Status parse_int(const std::string& flag, const std::string& v, long long lo, long long hi, long long* out) {
  char* end = nullptr;
  long long x = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0') return invalid_argument("--" + flag + ": '" + v + "' is not an integer");
  if (x < lo || x > hi)
    return invalid_argument("--" + flag + ": " + v + " is outside [" + std::to_string(lo) + ", " +
                            std::to_string(hi) + "]");
  *out = x;
  return Status::Ok();
}

}  // namespace

std::string server_usage() {
  return R"(usage: gdvr-server [flags]
  --listen=HOST:PORT        address to serve on (default 127.0.0.1:50051; port 0: any free port)
  --port-file=PATH          write the bound port here once serving
  --asset-root=DIR          scenes named by jobs must lie under it (default .)
  --output-root=DIR         frames go to DIR/<job id>/frame_0001.exr (default gdvr-output)
  --db=PATH                 SQLite job database (default <output-root>/gdvr.db)
  --ocio-config=PATH        OCIO config for previews and video (default: the shipped
                            data/ocio/config.ocio); $OCIO, when set, takes priority
  --concurrency=N           jobs rendering at once (default 1)
  --threads=N               render threads in all (default 0: all cores)
  --max-width=N --max-height=N --max-spp=N --max-frames=N
                            limits on what a job renders, after its scene and params
                            resolve (default 8192, 8192, 65536, 100000)
  --max-time-budget=S       largest time_budget_s per frame (default 86400)
  --max-work=N              largest frames x width x height x spp of a job
                            (default 10000000000000)
  --max-upload-bytes=N      largest uploaded bundle (default 256 MiB)
  --max-message-bytes=N --max-queue=N
  --upload-root=DIR         uploaded bundles (default <output-root>/uploads; never
                            inside --asset-root)
  --upload-quota-bytes=N --upload-quota-files=N
                            all uploaded bundles together (default 4 GiB, 10000 files)
  --upload-retention-s=S    bundles no queued or running job names are deleted once
                            this old (default 86400)
  --token-file=PATH         accepted bearer tokens, one per line
                            (also $GDVR_TOKENS, comma-separated); none: no auth
  --tls-cert=PEM --tls-key=PEM [--tls-ca=PEM]   TLS; with a CA, clients need certificates
  --shutdown-grace-s=S      deadline for in-flight calls on SIGTERM (default 10)
  --keepalive-time-s=S      ping interval for quiet connections (default 30)
  --memory-limit-mib=N      buffered T-GPT frames beyond N MiB (all running jobs
                            together) go to files and are read back by tiles
                            (default: no limit)
  --spill-dir=DIR           where those files go (default: the system's temporary folder)
)";
}

Expected<std::vector<std::string>> read_token_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return not_found("--token-file: cannot read '" + path + "'");
  std::vector<std::string> tokens;
  std::string line;
  while (std::getline(in, line)) {
    line = trim(line);
    if (line.empty() || line[0] == '#') continue;
    tokens.push_back(line);
  }
  if (tokens.empty()) return invalid_argument("--token-file: '" + path + "' holds no token");
  return tokens;
}

Expected<ServerConfig> parse_server_flags(int argc, char** argv) {
  ServerConfig c;
  std::string token_file;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") return failed_precondition(server_usage());
    if (arg.rfind("--", 0) != 0) return invalid_argument("unexpected argument '" + arg + "'");
    std::string flag = arg.substr(2), value;
    size_t eq = flag.find('=');
    if (eq != std::string::npos) {
      value = flag.substr(eq + 1);
      flag = flag.substr(0, eq);
    } else if (i + 1 < argc) {
      value = argv[++i];
    } else {
      return invalid_argument("--" + flag + " needs a value");
    }
    long long n = 0;
    auto as_int = [&](long long lo, long long hi) { return parse_int(flag, value, lo, hi, &n); };
    if (flag == "listen") c.listen = value;
    else if (flag == "port-file") c.port_file = value;
    else if (flag == "asset-root") c.asset_root = value;
    else if (flag == "output-root") c.output_root = value;
    else if (flag == "db") c.db_path = value;
    else if (flag == "ocio-config") c.ocio_config = value;
    else if (flag == "token-file") token_file = value;
    else if (flag == "tls-cert") c.tls_cert = value;
    else if (flag == "tls-key") c.tls_key = value;
    else if (flag == "tls-ca") c.tls_ca = value;
    else if (flag == "concurrency") { GDVR_RETURN_IF_ERROR(as_int(1, 256)); c.concurrency = int(n); }
    else if (flag == "threads") { GDVR_RETURN_IF_ERROR(as_int(0, 4096)); c.threads = int(n); }
    else if (flag == "max-width") { GDVR_RETURN_IF_ERROR(as_int(1, 1 << 20)); c.limits.max_width = int(n); }
    else if (flag == "max-height") { GDVR_RETURN_IF_ERROR(as_int(1, 1 << 20)); c.limits.max_height = int(n); }
    else if (flag == "max-spp") { GDVR_RETURN_IF_ERROR(as_int(1, 1 << 30)); c.limits.max_spp = int(n); }
    else if (flag == "max-frames") { GDVR_RETURN_IF_ERROR(as_int(1, 1 << 30)); c.limits.max_frames = size_t(n); }
    else if (flag == "max-time-budget") { GDVR_RETURN_IF_ERROR(as_int(1, 1ll << 31)); c.limits.max_time_budget_s = double(n); }
    else if (flag == "max-work") { GDVR_RETURN_IF_ERROR(as_int(1, 1ll << 62)); c.limits.max_work = uint64_t(n); }
    else if (flag == "upload-root") c.uploads.root = value;
    else if (flag == "upload-quota-bytes") { GDVR_RETURN_IF_ERROR(as_int(1, 1ll << 50)); c.uploads.quota_bytes = uint64_t(n); }
    else if (flag == "upload-quota-files") { GDVR_RETURN_IF_ERROR(as_int(1, 1ll << 32)); c.uploads.quota_files = uint64_t(n); }
    else if (flag == "upload-retention-s") { GDVR_RETURN_IF_ERROR(as_int(0, 1ll << 31)); c.uploads.retention_s = double(n); }
    else if (flag == "max-upload-bytes") { GDVR_RETURN_IF_ERROR(as_int(1, 1ll << 40)); c.limits.max_upload_bytes = uint64_t(n); }
    else if (flag == "max-message-bytes") { GDVR_RETURN_IF_ERROR(as_int(1 << 16, 1 << 30)); c.limits.max_message_bytes = int(n); }
    else if (flag == "max-queue") { GDVR_RETURN_IF_ERROR(as_int(1, 1 << 24)); c.limits.max_queue = size_t(n); }
    else if (flag == "shutdown-grace-s") { GDVR_RETURN_IF_ERROR(as_int(0, 3600)); c.shutdown_grace_s = double(n); }
    else if (flag == "keepalive-time-s") { GDVR_RETURN_IF_ERROR(as_int(1, 3600)); c.keepalive_time_s = int(n); }
    else if (flag == "memory-limit-mib") { GDVR_RETURN_IF_ERROR(as_int(0, 1ll << 30)); c.memory_limit_bytes = n << 20; }
    else if (flag == "spill-dir") c.spill_dir = value;
    else return invalid_argument("unknown flag --" + flag + " (see --help)");
  }
  if (!token_file.empty()) {
    auto tokens = read_token_file(token_file);
    if (!tokens.ok()) return tokens.status();
    c.tokens = std::move(*tokens);
  }
  // Secrets also come from the environment so they stay out of `ps` output.
  if (const char* env = std::getenv("GDVR_TOKENS")) {
    std::stringstream ss(env);
    std::string t;
    while (std::getline(ss, t, ','))
      if (!trim(t).empty()) c.tokens.push_back(trim(t));
  }
  if (c.tls_cert.empty() != c.tls_key.empty())
    return invalid_argument("--tls-cert and --tls-key go together");
  if (!c.tls_ca.empty() && c.tls_cert.empty()) return invalid_argument("--tls-ca needs --tls-cert and --tls-key");
  if (c.db_path.empty()) c.db_path = c.output_root + "/gdvr.db";
  if (c.uploads.root.empty()) c.uploads.root = c.output_root + "/uploads";
  return c;
}

}  // namespace gdvr::server
