// gdvr-server's options: flags (and GDVR_* environment variables for secrets),
// validated once at start-up.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/job/frame_denoiser.h"
#include "core/util/status.h"

#ifndef GDVR_SHIPPED_OCIO_CONFIG
#define GDVR_SHIPPED_OCIO_CONFIG "data/ocio/config.ocio"
#endif

namespace gdvr::server {

// Request limits: a request over one gets RESOURCE_EXHAUSTED naming the
// field, the flag, and where the value came from. Width, height and spp are
// checked on what will be rendered (after the scene and params resolve).
struct Limits {
  int max_width = 8192;
  int max_height = 8192;
  int max_spp = 1 << 16;
  size_t max_frames = 100000;
  double max_time_budget_s = 86400;   // a job's time_budget_s (per frame)
  // frames x width x height x spp: the total samples of a job, what a farm
  // admin means by "too big" (each per-field limit alone lets 100000 frames
  // of 8192x8192 at 65536 spp through).
  uint64_t max_work = 10'000'000'000'000ull;
  uint64_t max_upload_bytes = 256ull << 20;  // one bundle
  int max_message_bytes = 8 << 20;  // inbound gRPC message size
  size_t max_queue = 1000;          // queued (not yet running) jobs
};

// Uploaded scene bundles live in their own folder, apart from the operator's
// asset root, under quotas for the whole folder; bundles no queued or running
// job names are deleted once older than the retention.
struct UploadPolicy {
  std::string root;                       // default: <output-root>/uploads
  uint64_t quota_bytes = 4ull << 30;      // all bundles together
  uint64_t quota_files = 10000;           // all bundles together
  double retention_s = 86400;             // for bundles no unfinished job names
};

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";  // "host:0" picks a free port
  std::string port_file;                   // when set, the bound port is written here
  std::string asset_root = ".";            // jobs name scenes under it
  std::string output_root = "gdvr-output"; // <output_root>/<job id>/frame_0001.exr
  std::string db_path;                     // default: <output_root>/gdvr.db
  // OCIO config for previews and video; $OCIO, when set, takes priority (the
  // VFX-wide convention). Default: the config shipped in data/ocio.
  std::string ocio_config = GDVR_SHIPPED_OCIO_CONFIG;
  int concurrency = 1;                     // jobs rendering at once
  int threads = 0;                         // render threads in all; 0: all cores
  Limits limits;
  UploadPolicy uploads;
  std::vector<std::string> tokens;         // accepted bearer tokens; empty: no auth
  std::string tls_cert, tls_key, tls_ca;   // TLS when cert+key; mTLS when also CA
  double shutdown_grace_s = 10;            // Shutdown() deadline on SIGTERM
  int keepalive_time_s = 30;               // server pings idle streams this often
  // Buffered T-GPT frames beyond this many bytes (all running jobs together,
  // split evenly between them) go to unnamed files in spill_dir (empty: the
  // system's temporary folder) and the window solve reads them by tiles
  // (docs/tgpt.md, "Memory"). < 0: no limit.
  long long memory_limit_bytes = -1;
  std::string spill_dir;
  // Not a flag: the denoiser server_main lends every job (Intel Open Image
  // Denoise where the build has it; empty otherwise), for T-GPT's denoised
  // data term (reconstruction.data_term).
  FrameDenoiser denoiser;
};

// Parses argv; `--help` yields a kFailedPrecondition status carrying the usage.
Expected<ServerConfig> parse_server_flags(int argc, char** argv);
std::string server_usage();

// Reads tokens (one per line, '#' comments) from a file.
Expected<std::vector<std::string>> read_token_file(const std::string& path);

}  // namespace gdvr::server
