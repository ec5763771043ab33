// gdvr: command-line client of gdvr-server.
//   gdvr [global flags] submit|watch|status|list|cancel|fetch|upload ...
#include <google/protobuf/util/json_util.h>
#include <unistd.h>

#include <chrono>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <thread>
#include <vector>

#include "client/connection.h"
#include "client/frame_sink.h"
#include "client/health_check.h"
#include "client/progress_view.h"
#include "proto/job_state_name.h"

namespace fs = std::filesystem;
using namespace gdvr;
using namespace gdvr::client;

namespace {

const char* kUsage = R"(usage: gdvr [global flags] <command> [flags]

commands:
  submit [JOB.json] [--scene S --frames F --width W --height H --spp N --seed N
         --integrator pt|gpt|tgpt --priority P] [--key IDEMPOTENCY_KEY]
         [--upload-dir DIR]  upload DIR as a scene bundle; --scene is then relative to DIR
         [--watch [--out DIR] [--raw] [--no-artifacts]]
  watch JOB_ID [--out DIR] [--from FRAME] [--no-artifacts]
                                             resumes after the last frame in DIR
  status JOB_ID
  list [--state queued|running|cancelling|completed|failed|cancelled] [--limit N]
  cancel JOB_ID
  fetch JOB_ID --out DIR [--what frames,previews,video,stats]
                                             saves the job's files as they are now
  upload DIR --scene FILE                    prints the scene path to submit
  health [--wait SECONDS]                    exit 0 once the server reports SERVING

With --watch/watch and --out, frames are saved as they become final and, when
the job completes, its previews, video and stats.json are fetched into DIR too
(unless --no-artifacts).

global flags:
  --server HOST:PORT   (default $GDVR_SERVER or 127.0.0.1:50051)
  --token T | --token-file PATH   bearer token (default $GDVR_TOKEN)
  --tls-ca PEM [--tls-cert PEM --tls-key PEM]

exit codes: 0 ok, 1 job failed or cancelled, 2 usage, 3 server unreachable,
            4 authentication failed, 5 request rejected (invalid job), 6 other error
)";

struct Args {
  std::vector<std::string> positional;
  std::map<std::string, std::string> flags;
  bool has(const std::string& k) const { return flags.count(k) > 0; }
  std::string get(const std::string& k, const std::string& def = "") const {
    auto it = flags.find(k);
    return it == flags.end() ? def : it->second;
  }
};

const std::vector<std::string> kBoolFlags = {"watch", "raw", "help", "no-artifacts"};

bool parse_args(int argc, char** argv, int start, Args* out, std::string* err) {
  for (int i = start; i < argc; ++i) {
    std::string a = argv[i];
    if (a.rfind("--", 0) != 0) {
      out->positional.push_back(a);
      continue;
    }
    std::string k = a.substr(2), v;
    size_t eq = k.find('=');
    bool is_bool = std::find(kBoolFlags.begin(), kBoolFlags.end(), k) != kBoolFlags.end();
    if (eq != std::string::npos) {
      v = k.substr(eq + 1);
      k = k.substr(0, eq);
    } else if (!is_bool) {
      if (i + 1 >= argc) {
        *err = "--" + k + " needs a value";
        return false;
      }
      v = argv[++i];
    }
    out->flags[k] = v;
  }
  return true;
}

std::string random_key() {
  std::random_device rd;
  char buf[40];
  std::snprintf(buf, sizeof buf, "cli-%08x%08x%08x", rd(), rd(), rd());
  return buf;
}

// ---- Progress display ----

// Draws ProgressView's line: redrawn in place on a terminal; in logs, one
// line per final frame (not per tick).
class ProgressBar {
 public:
  ProgressBar() : tty_(isatty(STDERR_FILENO)), start_(std::chrono::steady_clock::now()) {}
  void on_event(const v1::JobEvent& ev) { view_.on_event(ev, now()); }
  void draw(const std::string& note) {
    std::string line = view_.line(now(), note);
    if (tty_) std::fprintf(stderr, "\r%-110s", line.c_str());
    else if (!note.empty()) std::fprintf(stderr, "%s\n", line.c_str());
    std::fflush(stderr);
  }
  void done() {
    if (tty_) std::fprintf(stderr, "\n");
  }

 private:
  double now() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  bool tty_;
  std::chrono::steady_clock::time_point start_;
  ProgressView view_;
};

// ---- Artifacts ----

const char* kind_name(v1::ArtifactKind k) {
  switch (k) {
    case v1::ARTIFACT_KIND_FRAME: return "frames";
    case v1::ARTIFACT_KIND_PREVIEW: return "previews";
    case v1::ARTIFACT_KIND_VIDEO: return "video";
    case v1::ARTIFACT_KIND_STATS: return "stats";
    default: return "other";
  }
}

// Saves the job's files (of `kinds`; empty: all) into `out_dir`, each through
// a temporary name and rename so the folder never holds half a file.
int fetch_artifacts(Connection& conn, const std::string& job_id, const std::vector<v1::ArtifactKind>& kinds,
                    const std::string& out_dir) {
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) {
    std::fprintf(stderr, "gdvr: fetch: cannot create '%s': %s\n", out_dir.c_str(), ec.message().c_str());
    return kExitError;
  }
  v1::FetchArtifactsRequest req;
  req.set_job_id(job_id);
  for (auto k : kinds) req.add_kinds(k);
  auto ctx = conn.context(/* deadline_s = */ 0);
  auto reader = conn.stub()->FetchArtifacts(ctx.get(), req);
  v1::ArtifactChunk c;
  std::ofstream file;
  std::string name, tmp;
  uint64_t written = 0;
  std::map<std::string, int> counts;
  auto fail = [&](const std::string& msg) {
    ctx->TryCancel();
    file.close();
    if (!tmp.empty()) fs::remove(tmp, ec);
    std::fprintf(stderr, "gdvr: fetch %s: %s\n", job_id.c_str(), msg.c_str());
    return kExitError;
  };
  while (reader->Read(&c)) {
    if (c.offset() == 0) {
      name = c.file_name();
      // The server names files inside the job folder; refuse anything else.
      if (name.empty() || name.find('/') != std::string::npos || name == "." || name == "..")
        return fail("refusing file name '" + name + "'");
      tmp = out_dir + "/." + name + ".part";
      file = std::ofstream(tmp, std::ios::binary | std::ios::trunc);
      written = 0;
      if (!file) return fail("cannot write '" + tmp + "'");
    }
    if (c.file_name() != name || c.offset() != written) return fail("out-of-order chunk of " + c.file_name());
    file.write(c.data().data(), std::streamsize(c.data().size()));
    written += c.data().size();
    if (c.last()) {
      file.close();
      if (!file || written != c.total_size()) return fail("short write of " + name);
      fs::rename(tmp, out_dir + "/" + name, ec);
      if (ec) return fail("cannot rename into '" + out_dir + "/" + name + "': " + ec.message());
      tmp.clear();
      ++counts[kind_name(c.kind())];
    }
  }
  grpc::Status st = reader->Finish();
  if (!st.ok()) {
    if (!tmp.empty()) fs::remove(tmp, ec);
    return report_rpc_error("fetch " + job_id, st, conn.options());
  }
  std::string summary;
  for (const auto& [k, n] : counts) summary += (summary.empty() ? "" : ", ") + std::to_string(n) + " " + k;
  std::fprintf(stderr, "gdvr: fetched %s into %s\n", summary.empty() ? "nothing" : summary.c_str(), out_dir.c_str());
  return kExitOk;
}

// ---- Watching ----

// Streams a job's events into `out_dir`, reconnecting (and resuming after the
// last saved frame) when the server goes away, e.g. during a restart.
int watch_job(Connection& conn, const std::string& job_id, const std::string& out_dir, int from_frame,
              bool stop_when_caught_up = false, int caught_up_frames = 0, bool fetch_outputs = false) {
  ProgressBar bar;
  FrameSink sink(out_dir);
  int next = from_frame;
  int received = 0;
  int failures = 0;
  for (;;) {
    v1::WatchJobRequest req;
    req.set_job_id(job_id);
    if (next >= 0) req.set_from_frame(next);
    auto ctx = conn.context(/* deadline_s = */ 0);
    auto reader = conn.stub()->WatchJob(ctx.get(), req);
    v1::JobEvent ev;
    bool any = false;
    while (reader->Read(&ev)) {
      any = true;
      failures = 0;
      switch (ev.event_case()) {
        case v1::JobEvent::kQueued:
          std::fprintf(stderr, "gdvr: job %s queued (position %d)\n", job_id.c_str(), ev.queued().queue_position());
          break;
        case v1::JobEvent::kStarted:
          bar.on_event(ev);
          std::fprintf(stderr, "gdvr: job %s running, %d frames%s\n", job_id.c_str(), ev.started().frames_total(),
                       ev.started().skipped_frames_size()
                           ? (" (" + std::to_string(ev.started().skipped_frames_size()) + " already final)").c_str()
                           : "");
          break;
        case v1::JobEvent::kFrameRendered:
          bar.on_event(ev);
          bar.draw("");
          break;
        case v1::JobEvent::kFrameFinal: {
          int done = INT_MIN;
          std::string err;
          if (!sink.add(ev.frame_final(), &done, &err)) {
            bar.done();
            std::fprintf(stderr, "gdvr: watch %s: %s\n", job_id.c_str(), err.c_str());
            ctx->TryCancel();
            return kExitError;
          }
          if (done != INT_MIN) {
            next = done + 1;
            ++received;
            bar.on_event(ev);
            bar.draw("frame " + std::to_string(done));
            if (stop_when_caught_up && received >= caught_up_frames) {
              ctx->TryCancel();
              bar.done();
              return kExitOk;
            }
          }
          break;
        }
        case v1::JobEvent::kCompleted:
          bar.on_event(ev);
          bar.draw("");
          bar.done();
          std::fprintf(stderr, "gdvr: job %s completed%s%s\n", job_id.c_str(), out_dir.empty() ? "" : "; frames in ",
                       out_dir.c_str());
          // Frames came with the stream; the rest is made at completion.
          if (fetch_outputs && !out_dir.empty())
            return fetch_artifacts(conn, job_id,
                                   {v1::ARTIFACT_KIND_PREVIEW, v1::ARTIFACT_KIND_VIDEO, v1::ARTIFACT_KIND_STATS},
                                   out_dir);
          return kExitOk;
        case v1::JobEvent::kFailed:
          bar.done();
          std::fprintf(stderr, "gdvr: job %s failed (%s): %s\n", job_id.c_str(), ev.failed().code().c_str(),
                       ev.failed().reason().c_str());
          return kExitJobFailed;
        case v1::JobEvent::kCancelled:
          bar.done();
          std::fprintf(stderr, "gdvr: job %s cancelled: %s\n", job_id.c_str(), ev.cancelled().reason().c_str());
          return kExitJobFailed;
        default:
          break;
      }
    }
    grpc::Status st = reader->Finish();
    bool transient = st.error_code() == grpc::StatusCode::UNAVAILABLE;
    if (stop_when_caught_up && st.ok()) return kExitOk;
    // A dropped stream or restarting server: retry with backoff, resuming.
    if (transient && failures < 30) {
      ++failures;
      if (any || failures == 1)
        std::fprintf(stderr, "\ngdvr: connection lost (%s); resuming from frame %d\n", st.error_message().c_str(),
                     next);
      std::this_thread::sleep_for(std::chrono::milliseconds(std::min(2000, 200 * failures)));
      continue;
    }
    bar.done();
    if (st.ok()) {
      std::fprintf(stderr, "gdvr: watch %s: stream ended without a final state\n", job_id.c_str());
      return kExitError;
    }
    return report_rpc_error("watch " + job_id, st, conn.options());
  }
}

// ---- Verbs ----

bool read_file(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return true;
}

int upload_dir(Connection& conn, const std::string& dir, const std::string& scene_file, std::string* scene_out) {
  std::vector<std::string> files;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); it != fs::recursive_directory_iterator(); ++it)
    if (it->is_regular_file()) files.push_back(fs::relative(it->path(), dir).generic_string());
  if (ec) {
    std::fprintf(stderr, "gdvr: upload: cannot read folder '%s': %s\n", dir.c_str(), ec.message().c_str());
    return kExitUsage;
  }
  auto ctx = conn.context(/* deadline_s = */ 600);
  v1::UploadSceneResponse resp;
  auto writer = conn.stub()->UploadScene(ctx.get(), &resp);
  bool first = true;
  for (const auto& f : files) {
    std::ifstream in(fs::path(dir) / f, std::ios::binary);
    std::vector<char> buf(1 << 20);
    bool sent_any = false;
    while (in || !sent_any) {
      in.read(buf.data(), std::streamsize(buf.size()));
      v1::UploadSceneChunk c;
      if (first) c.set_scene_file(scene_file);
      first = false;
      c.set_path(f);
      c.set_data(buf.data(), size_t(in.gcount()));
      sent_any = true;
      if (!writer->Write(c)) break;
      if (in.gcount() == 0) break;
    }
  }
  writer->WritesDone();
  grpc::Status st = writer->Finish();
  if (!st.ok()) return report_rpc_error("upload " + dir, st, conn.options());
  std::fprintf(stderr, "gdvr: uploaded %d files (%llu bytes), bundle %s\n", resp.files(),
               static_cast<unsigned long long>(resp.total_bytes()), resp.bundle_hash().c_str());
  *scene_out = resp.scene();
  return kExitOk;
}

int cmd_submit(Connection& conn, const Args& a) {
  v1::SubmitJobRequest req;
  req.set_idempotency_key(a.get("key", random_key()));
  v1::JobSpec spec;
  std::string job_text;
  if (!a.positional.empty()) {
    if (!read_file(a.positional[0], &job_text)) {
      std::fprintf(stderr, "gdvr: submit: cannot read job file '%s'\n", a.positional[0].c_str());
      return kExitUsage;
    }
    // Parsed here only to apply flag overrides; the server re-parses and
    // reports unknown fields by name.
    google::protobuf::util::JsonParseOptions po;
    auto st = google::protobuf::util::JsonStringToMessage(job_text, &spec, po);
    if (!st.ok()) {
      std::fprintf(stderr, "gdvr: submit: %s: invalid job file: %s\n", a.positional[0].c_str(),
                   std::string(st.message()).c_str());
      return kExitRejected;
    }
  }
  try {
    if (a.has("scene")) spec.set_scene(a.get("scene"));
    if (a.has("frames")) spec.set_frames(a.get("frames"));
    if (a.has("fps")) spec.set_fps(std::stod(a.get("fps")));
    if (a.has("width")) spec.set_width(std::stoi(a.get("width")));
    if (a.has("height")) spec.set_height(std::stoi(a.get("height")));
    if (a.has("spp")) spec.set_spp(std::stoi(a.get("spp")));
    if (a.has("seed")) spec.set_seed(std::stoull(a.get("seed")));
    if (a.has("integrator")) spec.set_integrator(a.get("integrator"));
    if (a.has("shift")) spec.set_shift(a.get("shift"));
    if (a.has("priority")) spec.set_priority(std::stoi(a.get("priority")));
  } catch (const std::exception&) {
    std::fprintf(stderr, "gdvr: submit: a numeric flag has a non-numeric value\n");
    return kExitUsage;
  }
  if (a.has("upload-dir")) {
    std::string scene;
    int rc = upload_dir(conn, a.get("upload-dir"), spec.scene(), &scene);
    if (rc != kExitOk) return rc;
    spec.set_scene(scene);
  }
  if (spec.scene().empty()) {
    std::fprintf(stderr, "gdvr: submit: no scene (give a job file or --scene)\n");
    return kExitUsage;
  }
  bool overridden = a.has("scene") || a.has("frames") || a.has("fps") || a.has("width") || a.has("height") ||
                    a.has("spp") || a.has("seed") || a.has("integrator") || a.has("shift") || a.has("priority") ||
                    a.has("upload-dir");
  if (!job_text.empty() && !overridden) req.set_job_json(job_text);
  else *req.mutable_job() = spec;
  v1::SubmitJobResponse resp;
  auto ctx = conn.context();
  grpc::Status st = conn.stub()->SubmitJob(ctx.get(), req, &resp);
  if (!st.ok()) return report_rpc_error("submit", st, conn.options());
  std::printf("%s\n", resp.job_id().c_str());
  std::fflush(stdout);
  std::fprintf(stderr, "gdvr: %s job %s (%d frames)\n", resp.existing() ? "existing" : "submitted",
               resp.job_id().c_str(), resp.job().frames_size());
  if (!a.has("watch")) return kExitOk;
  return watch_job(conn, resp.job_id(), a.get("out"), -1, false, 0, !a.has("no-artifacts"));
}

int cmd_watch(Connection& conn, const Args& a) {
  if (a.positional.empty()) return std::fprintf(stderr, "gdvr: watch: missing JOB_ID\n"), kExitUsage;
  std::string out = a.get("out");
  int from = a.has("from") ? std::atoi(a.get("from").c_str()) : (out.empty() ? -1 : FrameSink::resume_frame(out));
  if (from >= 0 && !a.has("from")) std::fprintf(stderr, "gdvr: resuming from frame %d\n", from);
  return watch_job(conn, a.positional[0], out, from, false, 0, !a.has("no-artifacts"));
}

// Final frames and rendering progress apart (Progress in the proto): for
// tgpt the first trails the second by up to a reconstruction window.
void print_job(const v1::Job& j) {
  int rendered = std::max(j.progress().frames_rendered(), j.final_frames_size());
  std::printf("%s  %-10s  final %d/%d  rendered %d/%d  priority %d  scene %s%s%s\n", j.id().c_str(),
              job_state_name(j.state()).c_str(), j.final_frames_size(), j.frames_size(), rendered, j.frames_size(), j.priority(),
              j.spec().scene().c_str(), j.reason().empty() ? "" : "  reason: ", j.reason().c_str());
}

int cmd_status(Connection& conn, const Args& a) {
  if (a.positional.empty()) return std::fprintf(stderr, "gdvr: status: missing JOB_ID\n"), kExitUsage;
  v1::GetJobRequest req;
  req.set_job_id(a.positional[0]);
  v1::Job job;
  auto ctx = conn.context();
  grpc::Status st = conn.stub()->GetJob(ctx.get(), req, &job);
  if (!st.ok()) return report_rpc_error("status " + a.positional[0], st, conn.options());
  print_job(job);
  if (job.state() == v1::JOB_STATE_RUNNING)
    std::printf("  ETA %s, output %s\n", format_duration(job.progress().eta_seconds()).c_str(), job.output_dir().c_str());
  return kExitOk;
}

int cmd_list(Connection& conn, const Args& a) {
  v1::ListJobsRequest req;
  if (a.has("state")) {
    v1::JobState s;
    std::string name = "JOB_STATE_" + a.get("state");
    for (auto& c : name) c = char(std::toupper(static_cast<unsigned char>(c)));
    if (!v1::JobState_Parse(name, &s)) return std::fprintf(stderr, "gdvr: list: unknown --state\n"), kExitUsage;
    req.add_states(s);
  }
  int limit = a.has("limit") ? std::atoi(a.get("limit").c_str()) : 1000000;
  int shown = 0;
  do {
    req.set_page_size(std::min(100, limit - shown));
    v1::ListJobsResponse resp;
    auto ctx = conn.context();
    grpc::Status st = conn.stub()->ListJobs(ctx.get(), req, &resp);
    if (!st.ok()) return report_rpc_error("list", st, conn.options());
    for (const auto& j : resp.jobs()) print_job(j), ++shown;
    req.set_page_token(resp.next_page_token());
  } while (!req.page_token().empty() && shown < limit);
  return kExitOk;
}

int cmd_cancel(Connection& conn, const Args& a) {
  if (a.positional.empty()) return std::fprintf(stderr, "gdvr: cancel: missing JOB_ID\n"), kExitUsage;
  v1::CancelJobRequest req;
  req.set_job_id(a.positional[0]);
  v1::Job job;
  auto ctx = conn.context();
  grpc::Status st = conn.stub()->CancelJob(ctx.get(), req, &job);
  if (!st.ok()) return report_rpc_error("cancel " + a.positional[0], st, conn.options());
  std::fprintf(stderr, "gdvr: %s is %s\n", job.id().c_str(), job_state_name(job.state()).c_str());
  return kExitOk;
}

int cmd_fetch(Connection& conn, const Args& a) {
  if (a.positional.empty() || !a.has("out"))
    return std::fprintf(stderr, "gdvr: fetch: usage: gdvr fetch JOB_ID --out DIR [--what ...]\n"), kExitUsage;
  std::vector<v1::ArtifactKind> kinds;
  std::stringstream what(a.get("what"));
  std::string w;
  while (std::getline(what, w, ',')) {
    if (w == "frames") kinds.push_back(v1::ARTIFACT_KIND_FRAME);
    else if (w == "previews") kinds.push_back(v1::ARTIFACT_KIND_PREVIEW);
    else if (w == "video") kinds.push_back(v1::ARTIFACT_KIND_VIDEO);
    else if (w == "stats") kinds.push_back(v1::ARTIFACT_KIND_STATS);
    else if (!w.empty())
      return std::fprintf(stderr, "gdvr: fetch: --what takes frames,previews,video,stats, not '%s'\n", w.c_str()),
             kExitUsage;
  }
  return fetch_artifacts(conn, a.positional[0], kinds, a.get("out"));
}

// grpc.health.v1.Health/Check over the CLI's channel settings (TLS CA only:
// health needs no token).
std::string health_check(const ConnectionOptions& opts, std::string* error) {
  std::shared_ptr<grpc::ChannelCredentials> creds = grpc::InsecureChannelCredentials();
  if (!opts.tls_ca.empty()) {
    grpc::SslCredentialsOptions ssl;
    std::ifstream in(opts.tls_ca);
    std::ostringstream ss;
    ss << in.rdbuf();
    ssl.pem_root_certs = ss.str();
    creds = grpc::SslCredentials(ssl);
  }
  auto channel = grpc::CreateCustomChannel(opts.server, creds, grpc::ChannelArguments());
  const std::string status = check_health(channel, std::chrono::seconds(3), error);
  return status.empty() ? "UNREACHABLE" : status;
}

int cmd_health(const ConnectionOptions& opts, const Args& a) {
  double wait_s = a.has("wait") ? std::atof(a.get("wait").c_str()) : 0;
  auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(int64_t(wait_s * 1000));
  std::string status, error;
  for (;;) {
    status = health_check(opts, &error);
    if (status == "SERVING" || std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  std::printf("%s\n", status.c_str());
  if (status == "SERVING") return kExitOk;
  if (status == "UNREACHABLE") {
    std::fprintf(stderr, "gdvr: health: cannot reach gdvr-server at %s (%s)\n", opts.server.c_str(), error.c_str());
    return kExitUnreachable;
  }
  return kExitError;
}

int cmd_upload(Connection& conn, const Args& a) {
  if (a.positional.empty() || !a.has("scene"))
    return std::fprintf(stderr, "gdvr: upload: usage: gdvr upload DIR --scene FILE\n"), kExitUsage;
  std::string scene;
  int rc = upload_dir(conn, a.positional[0], a.get("scene"), &scene);
  if (rc == kExitOk) std::printf("%s\n", scene.c_str());
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  // Global flags come before the command.
  ConnectionOptions opts;
  if (const char* s = std::getenv("GDVR_SERVER")) opts.server = s;
  if (const char* t = std::getenv("GDVR_TOKEN")) opts.token = t;
  int i = 1;
  for (; i < argc; ++i) {
    std::string a = argv[i];
    auto value = [&](std::string* out) {
      if (i + 1 >= argc) return false;
      *out = argv[++i];
      return true;
    };
    if (a == "-h" || a == "--help") return std::fputs(kUsage, stdout), kExitOk;
    if (a.rfind("--", 0) != 0) break;
    std::string v;
    bool ok = true;
    if (a == "--server") ok = value(&opts.server);
    else if (a == "--token") ok = value(&opts.token);
    else if (a == "--token-file") {
      ok = value(&v);
      std::ifstream in(v);
      if (!in || !std::getline(in, opts.token)) {
        std::fprintf(stderr, "gdvr: --token-file: cannot read '%s'\n", v.c_str());
        return kExitUsage;
      }
    } else if (a == "--tls-ca") ok = value(&opts.tls_ca);
    else if (a == "--tls-cert") ok = value(&opts.tls_cert);
    else if (a == "--tls-key") ok = value(&opts.tls_key);
    else {
      std::fprintf(stderr, "gdvr: unknown global flag %s\n%s", a.c_str(), kUsage);
      return kExitUsage;
    }
    if (!ok) return std::fprintf(stderr, "gdvr: %s needs a value\n", a.c_str()), kExitUsage;
  }
  if (i >= argc) return std::fputs(kUsage, stderr), kExitUsage;
  std::string cmd = argv[i];
  Args args;
  std::string err;
  if (!parse_args(argc, argv, i + 1, &args, &err)) return std::fprintf(stderr, "gdvr: %s\n", err.c_str()), kExitUsage;
  if (args.has("help")) return std::fputs(kUsage, stdout), kExitOk;
  Connection conn(opts);
  if (cmd == "submit") return cmd_submit(conn, args);
  if (cmd == "watch") return cmd_watch(conn, args);
  if (cmd == "status") return cmd_status(conn, args);
  if (cmd == "list") return cmd_list(conn, args);
  if (cmd == "cancel") return cmd_cancel(conn, args);
  if (cmd == "fetch") return cmd_fetch(conn, args);
  if (cmd == "upload") return cmd_upload(conn, args);
  if (cmd == "health") return cmd_health(opts, args);
  std::fprintf(stderr, "gdvr: unknown command '%s'\n%s", cmd.c_str(), kUsage);
  return kExitUsage;
}
