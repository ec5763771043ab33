#include "server/job_manager.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "core/io/atomic_file.h"
#include "core/io/image_io.h"
#include "core/job/job_outputs.h"
#include "core/image/error_metrics.h"
#include "core/util/echo_text.h"
#include "core/util/path_confinement.h"
#include "proto/job_state_name.h"
#include "server/log.h"
#include "server/scene_location.h"
#include "server/status_map.h"
#include "server/translate.h"

namespace gdvr::server {
namespace fs = std::filesystem;

namespace {

constexpr size_t kChunkBytes = 1 << 20;  // the API promises chunks of at most 1 MiB
// Progress changes once per tile. Watchers get at most one FrameRendered per
// interval (coalesced), and the render thread wakes them at most this often:
// per-tile wake-ups of every watcher cost measurable render time (see
// docs/service.md, streaming benchmark).
constexpr auto kProgressEventInterval = std::chrono::milliseconds(250);
constexpr auto kProgressNotifyInterval = std::chrono::milliseconds(50);

int64_t now_ms() {
  using namespace std::chrono;
  return duration_cast<milliseconds>(system_clock::now().time_since_epoch()).count();
}

int64_t now_us() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

std::string new_job_id() {
  static std::mutex mu;
  static std::mt19937_64 rng(std::random_device{}() ^ uint64_t(now_ms()));
  std::lock_guard<std::mutex> lock(mu);
  char buf[32];
  std::snprintf(buf, sizeof buf, "job-%016llx", static_cast<unsigned long long>(rng()));
  return buf;
}

bool is_terminal(v1::JobState s) {
  return s == v1::JOB_STATE_COMPLETED || s == v1::JOB_STATE_FAILED || s == v1::JOB_STATE_CANCELLED;
}

bool read_file(const std::string& path, std::string* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  *out = ss.str();
  return bool(in) || in.eof();
}

}  // namespace

JobManager::JobManager(ServerConfig config, std::unique_ptr<JobStore> store, UploadStore* uploads)
    : config_(std::move(config)), store_(std::move(store)), uploads_(uploads), client_text_(config_) {}

JobManager::~JobManager() { shutdown(); }

std::string JobManager::job_dir(const std::string& id) const { return config_.output_root + "/" + id; }

// ---- Validation ----

namespace {

std::string with_origin(long long value, const std::string& origin) {
  return std::to_string(value) + " (from " + origin + ")";
}

// "86400", "1.5e+13": whole up to a million, else 4 significant digits.
std::string approx(double v) {
  char buf[32];
  if (v == std::floor(v) && std::abs(v) < 1e6) std::snprintf(buf, sizeof buf, "%.0f", v);
  else std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

}  // namespace

Status JobManager::validate(const v1::JobSpec& spec, JobSpec* core_job, std::vector<int>* frames,
                            std::string* scene_root) const {
  const Limits& lim = config_.limits;
  if (spec.scene().empty()) return invalid_argument("scene: missing (a .xml path under the asset root)");
  // ---- What the job sets itself: refused before the scene is read ----
  if (spec.has_width() && spec.width() < 0) return invalid_argument("width: must be >= 0");
  if (spec.has_height() && spec.height() < 0) return invalid_argument("height: must be >= 0");
  if (spec.has_spp() && spec.spp() < 0) return invalid_argument("spp: must be >= 0");
  if (spec.width() > lim.max_width)
    return resource_exhausted("width: " + with_origin(spec.width(), "the job's width") +
                              " exceeds the server limit of " + std::to_string(lim.max_width) + " (--max-width)");
  if (spec.height() > lim.max_height)
    return resource_exhausted("height: " + with_origin(spec.height(), "the job's height") +
                              " exceeds the server limit of " + std::to_string(lim.max_height) + " (--max-height)");
  if (spec.spp() > lim.max_spp)
    return resource_exhausted("spp: " + with_origin(spec.spp(), "the job's spp") + " exceeds the server limit of " +
                              std::to_string(lim.max_spp) + " (--max-spp)");
  if (spec.has_time_budget_s() && !(spec.time_budget_s() >= 0 && std::isfinite(spec.time_budget_s())))
    return invalid_argument("time_budget_s: must be a non-negative number of seconds");
  if (spec.time_budget_s() > lim.max_time_budget_s)
    return resource_exhausted("time_budget_s: " + approx(spec.time_budget_s()) +
                              " s per frame exceeds the server limit of " + approx(lim.max_time_budget_s) +
                              " s (--max-time-budget)");
  if (spec.has_frames()) {
    // Before the job file is parsed, so the message names the server's limit.
    auto parsed = parse_frame_range(spec.frames(), lim.max_frames);
    if (!parsed.ok()) {
      const Status& st = parsed.status();
      return Status(st.code(), "frames: " + st.message() +
                                   (st.code() == StatusCode::kResourceExhausted ? " (--max-frames)" : ""));
    }
  }
  // ---- The scene: its name, its folder (asset root or upload bundle) ----
  auto loc = locate_scene(config_, spec.scene());
  if (!loc.ok()) return loc.status();
  if (uploads_ && !loc->upload_hash.empty()) uploads_->touch(loc->upload_hash);  // in use: restart its retention

  auto core = to_core_job(spec);
  if (!core.ok()) return core.status();
  core->scene = loc->relative;
  auto parsed = parse_frame_range(core->frames, lim.max_frames);
  if (!parsed.ok()) {
    const Status& s = parsed.status();
    return Status(s.code(), "frames: " + s.message());
  }
  if (parsed->empty()) return invalid_argument("frames: '" + echo_text(core->frames) + "' names no frame");
  JobRunOptions opts;
  opts.base_dir = loc->root;
  opts.asset_root = loc->root;
  opts.denoiser = config_.denoiser;
  // ---- What will be rendered, once the scene and its params resolve ----
  auto resolved = resolve_job(*core, opts);
  if (!resolved.ok()) return resolved.status();
  const ResolvedRender& r = *resolved;
  if (r.width.value > lim.max_width)
    return resource_exhausted("width: " + with_origin(r.width.value, r.width.origin) + " exceeds the server limit of " +
                              std::to_string(lim.max_width) + " (--max-width)");
  if (r.height.value > lim.max_height)
    return resource_exhausted("height: " + with_origin(r.height.value, r.height.origin) +
                              " exceeds the server limit of " + std::to_string(lim.max_height) + " (--max-height)");
  if (r.spp.value > lim.max_spp)
    return resource_exhausted("spp: " + with_origin(r.spp.value, r.spp.origin) + " exceeds the server limit of " +
                              std::to_string(lim.max_spp) + " (--max-spp)");
  // Samples in all (a double: the product of four limits overflows 64 bits).
  const double work = double(parsed->size()) * double(r.width.value) * double(r.height.value) * double(r.spp.value);
  if (work > double(lim.max_work))
    return resource_exhausted("job: " + std::to_string(parsed->size()) + " frames x " + std::to_string(r.width.value) +
                              "x" + std::to_string(r.height.value) + " x " + std::to_string(r.spp.value) + " spp = " +
                              approx(work) + " samples exceed the server limit of " + approx(double(lim.max_work)) +
                              " (--max-work); width from " + r.width.origin + ", height from " + r.height.origin +
                              ", spp from " + r.spp.origin);
  GDVR_RETURN_IF_ERROR(JobOutputs::validate(*core, {config_.ocio_config, config_.asset_root}, parsed->front()));
  if (core_job) *core_job = std::move(*core);
  if (frames) *frames = std::move(*parsed);
  if (scene_root) *scene_root = loc->root;
  return Status::Ok();
}

Status JobManager::locate_core(Job* job) {
  auto loc = locate_scene(config_, job->spec.scene());
  if (!loc.ok()) return loc.status();
  job->core.scene = loc->relative;
  job->scene_root = loc->root;
  return Status::Ok();
}

std::set<std::string> JobManager::uploads_in_use() const {
  std::set<std::string> out;
  const std::string prefix = kUploadScenePrefix;
  std::lock_guard<std::mutex> lock(mu_);
  for (const auto& [id, j] : jobs_) {
    if (is_terminal(j->state)) continue;
    const std::string& scene = j->spec.scene();
    if (scene.compare(0, prefix.size(), prefix) == 0)
      out.insert(scene.substr(prefix.size(), scene.find('/', prefix.size()) - prefix.size()));
  }
  return out;
}

// ---- Registry ----

Status JobManager::recover() {
  std::error_code ec;
  fs::create_directories(config_.output_root, ec);
  auto stored = store_->load_all();
  if (!stored.ok()) return stored.status();
  std::lock_guard<std::mutex> lock(mu_);
  for (auto& s : *stored) {
    auto job = std::make_unique<Job>();
    job->id = s.id;
    job->idempotency_key = s.idempotency_key;
    job->seq = s.seq;
    job->priority = s.priority;
    job->state = v1::JobState(s.state);
    job->spec_json = s.spec_json;
    job->reason = s.reason;
    job->reason_code = s.reason_code;
    job->created_ms = s.created_ms;
    job->started_ms = s.started_ms;
    job->finished_ms = s.finished_ms;
    for (auto& f : s.frames) {
      FrameRecord rec;
      rec.file = f.file;
      rec.size = f.size;
      rec.stats.ParseFromString(f.stats_pb);
      job->final_frames[f.frame] = std::move(rec);
    }
    next_seq_ = std::max(next_seq_, s.seq + 1);
    if (!s.idempotency_key.empty()) by_key_[s.idempotency_key] = s.id;
    Status st = Status::Ok();
    auto spec = job_spec_from_json(s.spec_json, "stored job " + s.id);
    if (spec.ok()) {
      job->spec = *spec;
      auto core = to_core_job(job->spec);
      if (core.ok()) {
        job->core = std::move(*core);
        auto frames = parse_frame_range(job->core.frames);
        if (frames.ok()) job->frames = std::move(*frames);
        else st = frames.status();
        // A finished job's scene may be gone (an expired upload); only an
        // unfinished one needs it.
        if (st.ok() && !is_terminal(job->state)) st = locate_core(job.get());
      } else {
        st = core.status();
      }
    } else {
      st = spec.status();
    }
    if (job->state == v1::JOB_STATE_COMPLETED && st.ok()) {
      std::string video = video_file_name(job->core.outputs.video_codec);
      if (!video.empty() && fs::exists(job_dir(job->id) + "/" + video, ec)) job->video_file = video;
    }
    job->progress.set_frames_total(int(job->frames.size()));
    job->progress.set_frames_done(int(job->final_frames.size()));
    job->progress.set_frames_rendered(int(job->final_frames.size()));
    job->progress.set_fraction(job->frames.empty() ? 0 : double(job->final_frames.size()) / job->frames.size());
    job->progress.set_eta_seconds(-1);
    Job* j = job.get();
    jobs_[s.id] = std::move(job);
    if (is_terminal(j->state)) continue;
    if (!st.ok()) {
      finish_locked(j, v1::JOB_STATE_FAILED, "cannot resume: " + st.message(),
                    grpc_code_name(to_grpc_code(st.code())));
      continue;
    }
    if (j->state == v1::JOB_STATE_CANCELLING) {
      // A client cancelled it and the server stopped before the render did.
      finish_locked(j, v1::JOB_STATE_CANCELLED, "cancelled by a client", "CANCELLED");
      continue;
    }
    // RUNNING at the time of a crash: back to the queue, resuming.
    j->state = v1::JOB_STATE_QUEUED;
    (void)persist_state_locked(*j);
    log_event("info", "job_recovered", {{"job", j->id}, {"final_frames", std::to_string(j->final_frames.size())},
                                        {"frames", std::to_string(j->frames.size())}});
  }
  return Status::Ok();
}

void JobManager::start() {
  for (int i = 0; i < config_.concurrency; ++i) workers_.emplace_back([this] { worker_loop(); });
}

void JobManager::shutdown() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_ && workers_.empty()) return;
    stopping_ = true;
    for (auto& [id, job] : jobs_)
      if (job->state == v1::JOB_STATE_RUNNING || job->state == v1::JOB_STATE_CANCELLING) job->cancel = true;
  }
  cv_.notify_all();
  for (auto& w : workers_) w.join();
  workers_.clear();
}

Expected<JobManager::Submitted> JobManager::submit(const std::string& key, const v1::JobSpec& spec) {
  std::string spec_json = job_spec_to_json(spec);
  auto existing = [&]() -> Expected<Submitted> {
    const Job& j = *jobs_.at(by_key_.at(key));
    if (j.spec_json != spec_json)
      return failed_precondition("idempotency_key: '" + echo_text(key) + "' was already used for a different job (" +
                                 j.id + ")");
    return Submitted{to_proto_locked(j), true};
  };
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return Status(StatusCode::kUnavailable, "server is shutting down");
    if (!key.empty() && by_key_.count(key)) return existing();
  }
  // Validation loads the scene: done outside the lock so other calls proceed.
  JobSpec core;
  std::vector<int> frames;
  std::string scene_root;
  GDVR_RETURN_IF_ERROR(validate(spec, &core, &frames, &scene_root));

  std::lock_guard<std::mutex> lock(mu_);
  if (!key.empty() && by_key_.count(key)) return existing();  // a concurrent retry won
  size_t queued = 0;
  for (const auto& [id, j] : jobs_) queued += j->state == v1::JOB_STATE_QUEUED;
  if (queued >= config_.limits.max_queue)
    return resource_exhausted("queue: " + std::to_string(queued) + " jobs are waiting (server limit " +
                              std::to_string(config_.limits.max_queue) + "); retry later");
  auto job = std::make_unique<Job>();
  job->id = new_job_id();
  job->idempotency_key = key;
  job->spec = spec;
  job->spec_json = spec_json;
  job->core = std::move(core);
  job->scene_root = std::move(scene_root);
  job->frames = std::move(frames);
  job->priority = job->core.priority;
  job->seq = next_seq_++;
  job->created_ms = now_ms();
  job->progress.set_frames_total(int(job->frames.size()));
  job->progress.set_eta_seconds(-1);
  StoredJob s;
  s.id = job->id;
  s.idempotency_key = key;
  s.seq = job->seq;
  s.priority = job->priority;
  s.state = job->state;
  s.spec_json = spec_json;
  s.created_ms = job->created_ms;
  GDVR_RETURN_IF_ERROR(store_->insert_job(s));
  Job* j = job.get();
  jobs_[j->id] = std::move(job);
  if (!key.empty()) by_key_[key] = j->id;
  log_event("info", "job_submitted", {{"job", j->id}, {"scene", j->spec.scene()}, {"frames", j->core.frames},
                                      {"priority", std::to_string(j->priority)}});
  Submitted out{to_proto_locked(*j), false};
  cv_.notify_all();
  return out;
}

Expected<v1::Job> JobManager::get(const std::string& id) const {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return not_found("job_id: no job '" + echo_text(id) + "'");
  return to_proto_locked(*it->second);
}

Expected<v1::ListJobsResponse> JobManager::list(const v1::ListJobsRequest& req) const {
  int page_size = req.page_size() <= 0 ? 50 : std::min(req.page_size(), 1000);
  int64_t below = INT64_MAX;  // the token is the seq to continue below (newest first)
  if (!req.page_token().empty()) {
    char* end = nullptr;
    below = std::strtoll(req.page_token().c_str(), &end, 10);
    if (*end != '\0' || below <= 0) return invalid_argument("page_token: '" + echo_text(req.page_token()) + "' is not valid");
  }
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<const Job*> all;
  for (const auto& [id, j] : jobs_) {
    if (j->seq >= below) continue;
    if (req.states_size() > 0 &&
        std::find(req.states().begin(), req.states().end(), j->state) == req.states().end())
      continue;
    all.push_back(j.get());
  }
  std::sort(all.begin(), all.end(), [](const Job* a, const Job* b) { return a->seq > b->seq; });
  v1::ListJobsResponse resp;
  for (size_t i = 0; i < all.size() && int(i) < page_size; ++i) *resp.add_jobs() = to_proto_locked(*all[i]);
  if (int(all.size()) > page_size) resp.set_next_page_token(std::to_string(all[size_t(page_size) - 1]->seq));
  return resp;
}

Expected<v1::Job> JobManager::cancel(const std::string& id) {
  std::unique_lock<std::mutex> lock(mu_);
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return not_found("job_id: no job '" + echo_text(id) + "'");
  Job* j = it->second.get();
  if (is_terminal(j->state))
    return failed_precondition("job '" + id + "' is already " + job_state_name(j->state));
  if (j->state == v1::JOB_STATE_QUEUED) {
    finish_locked(j, v1::JOB_STATE_CANCELLED, "cancelled by a client before it started", "CANCELLED");
  } else if (j->state == v1::JOB_STATE_RUNNING) {
    // The render stops at its next tile; until then the job is CANCELLING,
    // so neither this answer nor GetJob says RUNNING. Persisted, so that a
    // server stopped in between still ends the job as cancelled.
    j->cancel_requested = true;
    j->cancel = true;
    j->state = v1::JOB_STATE_CANCELLING;
    j->reason = "cancel requested by a client; stopping at the next tile";
    (void)persist_state_locked(*j);
    log_event("info", "job_cancel_requested", {{"job", id}});
  }  // CANCELLING already: the same answer again
  v1::Job out = to_proto_locked(*j);
  cv_.notify_all();
  return out;
}

// ---- Workers ----

JobManager::Job* JobManager::pick_next_locked() {
  Job* best = nullptr;
  for (auto& [id, j] : jobs_) {
    if (j->state != v1::JOB_STATE_QUEUED) continue;
    if (!best || j->priority > best->priority || (j->priority == best->priority && j->seq < best->seq))
      best = j.get();
  }
  return best;
}

void JobManager::worker_loop() {
  for (;;) {
    Job* job = nullptr;
    {
      std::unique_lock<std::mutex> lock(mu_);
      cv_.wait(lock, [&] { return stopping_ || (job = pick_next_locked()) != nullptr; });
      if (stopping_) return;
      job->state = v1::JOB_STATE_RUNNING;
      job->cancel = false;
      if (job->started_ms == 0) job->started_ms = now_ms();
      job->skipped.clear();
      for (const auto& [f, rec] : job->final_frames) job->skipped.push_back(f);
      (void)persist_state_locked(*job);
    }
    cv_.notify_all();
    log_event("info", "job_started", {{"job", job->id}, {"skip_frames", std::to_string(job->skipped.size())}});
    run(job);
  }
}

void JobManager::run(Job* job) {
  JobRunOptions opts;
  int hw = int(std::thread::hardware_concurrency());
  int threads = config_.threads > 0 ? config_.threads : hw;
  opts.threads = config_.concurrency > 1 ? std::max(1, threads / config_.concurrency) : config_.threads;
  opts.base_dir = job->scene_root;
  opts.asset_root = job->scene_root;
  opts.skip_frames = job->skipped;  // only this thread changes skipped while RUNNING
  // The memory limit covers every running job: each gets its share.
  if (config_.memory_limit_bytes >= 0) opts.memory_limit_bytes = config_.memory_limit_bytes / config_.concurrency;
  opts.spill_dir = config_.spill_dir;
  opts.denoiser = config_.denoiser;
  std::string dir = job_dir(job->id);
  std::error_code ec;
  fs::create_directories(dir, ec);
  remove_stale_temporaries(dir);

  Status frame_error = Status::Ok();
  auto fail_run = [&](const Status& st) {
    frame_error = st;
    job->cancel = true;
  };
  // Previews, video and relMSE. A fresh encoder per run: see job_outputs.h
  // for why that keeps the video whole across kill -9 and restart.
  std::unique_ptr<JobOutputs> outputs;
  if (auto o = JobOutputs::open(job->core, job->frames, dir, {config_.ocio_config, config_.asset_root}); o.ok())
    outputs = std::move(*o);
  else
    frame_error = o.status();
  JobCallbacks cb;
  cb.on_frame_final = [&](const FrameOutput& out) {
    if (!frame_error.ok()) return;
    // The EXR and its preview are written before the frame is persisted, so
    // every frame a restart treats as final has its preview too.
    auto written = outputs->write_frame(out);
    if (!written.ok()) return fail_run(written.status().with_context("frame " + std::to_string(out.frame) + " outputs: "));
    const std::string name = written->file;
    FrameRecord rec;
    rec.file = name;
    rec.size = written->bytes;
    to_proto(written->stats, &rec.stats);
    // Persist before announcing: a watcher must never be told about a frame
    // that a restart would forget.
    StoredFrame sf{out.frame, name, rec.size, rec.stats.SerializeAsString()};
    Status st = store_->insert_frame(job->id, sf);
    if (!st.ok()) return fail_run(st);
    {
      std::lock_guard<std::mutex> lock(mu_);
      rec.final_us = now_us();
      job->final_frames[out.frame] = rec;
      job->progress.set_frames_done(int(job->final_frames.size()));
      job->progress.set_frames_rendered(std::max(job->progress.frames_rendered(), int(job->final_frames.size())));
      ++job->progress_seq;
      write_stats_json(*job);
    }
    cv_.notify_all();
    log_event("info", "frame_final",
              {{"job", job->id}, {"frame", std::to_string(out.frame)},
               {"render_s", std::to_string(out.stats.render_seconds)}, {"bytes", std::to_string(rec.size)}});
    // After the announcement: encoding must not delay the watchers.
    st = outputs->add_to_video(out.frame);
    if (!st.ok()) return fail_run(st.with_context("frame " + std::to_string(out.frame) + ": "));
  };
  // Under a time budget, T-GPT's output waits for its window: the budget
  // reserves what writing a frame costs, timed on the first rendered one.
  cb.estimate_frame_final_seconds = [&](const FrameBuffers& buffers) {
    return outputs ? outputs->estimate_write_seconds(buffers.layers) : 0.0;
  };
  auto last_progress_notify = std::chrono::steady_clock::time_point{};
  cb.on_progress = [&](const JobProgress& p) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      to_proto(p, &job->progress);
      // Two stages, two counts (see Progress in the proto): core counts
      // rendered frames (including those final before a resume, and for
      // tgpt the window frames a resume renders again); final frames are
      // the job's own records.
      const int total = int(job->frames.size());
      const int final_count = int(job->final_frames.size());
      job->progress.set_frames_done(final_count);
      job->progress.set_frames_rendered(std::min(total, std::max(p.frames_done, final_count)));
      job->progress.set_frames_total(total);
      ++job->progress_seq;
    }
    auto now = std::chrono::steady_clock::now();
    if (now - last_progress_notify >= kProgressNotifyInterval) {
      last_progress_notify = now;
      cv_.notify_all();
    }
  };

  Status st = frame_error.ok() ? run_job(job->core, opts, cb, &job->cancel) : frame_error;
  std::string video;
  if (st.ok() && frame_error.ok()) {
    // Finishing (catch-up of frames an earlier run made final, trailer,
    // rename into place) happens before COMPLETED is announced, so a
    // completed job always has its video.
    auto v = outputs->finish();
    if (v.ok()) video = *v;
    else frame_error = v.status();
  }
  outputs.reset();  // an unfinished encoder deletes its partial file

  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!frame_error.ok()) {
      finish_locked(job, v1::JOB_STATE_FAILED, frame_error.message(),
                    grpc_code_name(to_grpc_code(frame_error.code())));
    } else if (st.ok()) {
      job->video_file = video;
      job->progress.set_fraction(1);
      job->progress.set_eta_seconds(0);
      finish_locked(job, v1::JOB_STATE_COMPLETED, "", "");
    } else if (st.code() == StatusCode::kCancelled && !job->cancel_requested) {
      // Shutdown: the frames so far are persisted; the next start resumes.
      job->state = v1::JOB_STATE_QUEUED;
      (void)persist_state_locked(*job);
      log_event("info", "job_checkpointed", {{"job", job->id}, {"final_frames", std::to_string(job->final_frames.size())}});
    } else if (st.code() == StatusCode::kCancelled) {
      finish_locked(job, v1::JOB_STATE_CANCELLED, "cancelled by a client", "CANCELLED");
    } else {
      finish_locked(job, v1::JOB_STATE_FAILED, st.message(), grpc_code_name(to_grpc_code(st.code())));
    }
  }
  cv_.notify_all();
}

void JobManager::finish_locked(Job* job, v1::JobState state, const std::string& reason, const std::string& code) {
  job->state = state;
  job->reason = reason;
  job->reason_code = code;
  job->finished_ms = now_ms();
  Status st = persist_state_locked(*job);
  if (!st.ok()) log_event("error", "persist_failed", {{"job", job->id}, {"error", st.message()}});
  write_stats_json(*job);
  log_event(state == v1::JOB_STATE_FAILED ? "warn" : "info", "job_finished",
            {{"job", job->id}, {"state", job_state_name(state)}, {"reason", reason},
             {"final_frames", std::to_string(job->final_frames.size())}});
}

Status JobManager::persist_state_locked(const Job& job) {
  return store_->update_job(job.id, job.state, job.reason, job.reason_code, job.started_ms, job.finished_ms);
}

void JobManager::write_stats_json(const Job& job) const {
  std::error_code ec;
  if (!fs::is_directory(job_dir(job.id), ec)) return;
  std::vector<WrittenFrame> frames;
  for (const auto& [f, rec] : job.final_frames) frames.push_back({rec.file, rec.size, from_proto(rec.stats)});
  std::vector<std::pair<std::string, std::string>> header = {
      {"job_id", job.id}, {"integrator", integrator_name(job.core.integrator)}, {"state", job_state_name(job.state)}};
  if (!job.reason.empty()) header.push_back({"reason", job.reason});
  (void)write_text_atomic(job_dir(job.id) + "/stats.json", stats_json(header, int(job.frames.size()), frames));
}

int JobManager::queue_position_locked(const Job& job) const {
  if (job.state != v1::JOB_STATE_QUEUED) return -1;
  int pos = 0;
  for (const auto& [id, j] : jobs_)
    if (j->state == v1::JOB_STATE_QUEUED &&
        (j->priority > job.priority || (j->priority == job.priority && j->seq < job.seq)))
      ++pos;
  return pos;
}

v1::Job JobManager::to_proto_locked(const Job& j) const {
  v1::Job out;
  out.set_id(j.id);
  out.set_state(j.state);
  *out.mutable_spec() = j.spec;
  out.set_idempotency_key(j.idempotency_key);
  out.set_priority(j.priority);
  for (int f : j.frames) out.add_frames(f);
  for (const auto& [f, rec] : j.final_frames) out.add_final_frames(f);
  *out.mutable_progress() = j.progress;
  out.set_reason(client_text_(j.reason));
  out.set_created_unix_ms(j.created_ms);
  out.set_started_unix_ms(j.started_ms);
  out.set_finished_unix_ms(j.finished_ms);
  out.set_output_dir(job_dir(j.id));
  out.set_queue_position(queue_position_locked(j));
  out.set_video_file(j.video_file);
  return out;
}

// ---- Artifacts ----

Expected<std::vector<JobManager::Artifact>> JobManager::artifacts(const std::string& id,
                                                                const std::vector<v1::ArtifactKind>& kinds) const {
  auto wanted = [&](v1::ArtifactKind k) {
    return kinds.empty() || std::find(kinds.begin(), kinds.end(), k) != kinds.end();
  };
  std::vector<Artifact> out;
  std::lock_guard<std::mutex> lock(mu_);
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return not_found("job_id: no job '" + echo_text(id) + "'");
  const Job& j = *it->second;
  // Names come from the job's own records, never from the request, so a
  // client cannot name a path outside the job's folder.
  std::string dir = job_dir(id);
  std::error_code ec;
  if (wanted(v1::ARTIFACT_KIND_FRAME))
    for (const auto& [f, rec] : j.final_frames) out.push_back({rec.file, v1::ARTIFACT_KIND_FRAME});
  if (wanted(v1::ARTIFACT_KIND_PREVIEW))
    for (const auto& [f, rec] : j.final_frames)
      if (fs::exists(dir + "/" + preview_file_name(f), ec)) out.push_back({preview_file_name(f), v1::ARTIFACT_KIND_PREVIEW});
  if (wanted(v1::ARTIFACT_KIND_VIDEO) && !j.video_file.empty()) out.push_back({j.video_file, v1::ARTIFACT_KIND_VIDEO});
  if (wanted(v1::ARTIFACT_KIND_STATS) && fs::exists(dir + "/stats.json", ec))
    out.push_back({"stats.json", v1::ARTIFACT_KIND_STATS});
  return out;
}

// ---- Watching ----

bool JobManager::send_frame(const Job& job, int frame, const FrameRecord& rec, bool raw,
                            const std::function<bool(const v1::JobEvent&)>& send, const v1::Progress& progress) {
  std::string path = job_dir(job.id) + "/" + rec.file;
  std::string exr;
  if (!read_file(path, &exr)) {
    log_event("error", "frame_unreadable", {{"job", job.id}, {"frame", std::to_string(frame)}, {"path", path}});
    return true;  // skip it rather than end the stream; GetJob still lists it
  }
  struct Payload {
    v1::FrameFinal::Payload kind;
    std::string bytes;
  };
  std::vector<Payload> payloads;
  payloads.push_back({v1::FrameFinal::PAYLOAD_EXR, std::move(exr)});
  int width = 0, height = 0;
  if (raw) {
    auto img = read_exr(path);
    const ImageLayer* main = img.ok() ? img->find("") : nullptr;
    if (main && main->image.channels() >= 3) {
      const Image& im = main->image;
      width = im.width();
      height = im.height();
      std::vector<float> rgb(im.pixel_count() * 3);
      for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
          for (int c = 0; c < 3; ++c) rgb[(size_t(y) * width + x) * 3 + c] = im.at(x, y, c);
      payloads.push_back({v1::FrameFinal::PAYLOAD_RAW_RGB_F32,
                          std::string(reinterpret_cast<const char*>(rgb.data()), rgb.size() * sizeof(float))});
    }
  }
  for (size_t p = 0; p < payloads.size(); ++p) {
    const std::string& bytes = payloads[p].bytes;
    size_t offset = 0;
    do {
      size_t n = std::min(kChunkBytes, bytes.size() - offset);
      v1::JobEvent ev;
      ev.set_job_id(job.id);
      auto* ff = ev.mutable_frame_final();
      ff->set_frame(frame);
      ff->set_payload(payloads[p].kind);
      ff->set_offset(offset);
      ff->set_total_size(bytes.size());
      ff->set_data(bytes.data() + offset, n);
      ff->set_file_name(rec.file);
      ff->set_width(width);
      ff->set_height(height);
      offset += n;
      if (p + 1 == payloads.size() && offset == bytes.size()) {
        ff->set_last(true);
        *ff->mutable_stats() = rec.stats;
        *ff->mutable_progress() = progress;
        ff->set_final_unix_us(rec.final_us);
      }
      if (!send(ev)) return false;
    } while (offset < bytes.size());
  }
  return true;
}

Status JobManager::watch(const v1::WatchJobRequest& req, const std::function<bool(const v1::JobEvent&)>& send,
                         const std::function<bool()>& client_gone) {
  const Job* job = nullptr;
  {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = jobs_.find(req.job_id());
    if (it == jobs_.end()) return not_found("job_id: no job '" + echo_text(req.job_id()) + "'");
    job = it->second.get();  // jobs are never erased: the pointer stays valid
  }
  int next_frame = req.has_from_frame() ? req.from_frame() : INT32_MIN;
  bool queued_sent = false, started_sent = false;
  uint64_t progress_sent = 0;
  auto next_progress_at = std::chrono::steady_clock::time_point{};
  for (;;) {
    // Snapshot under the lock, send without it: a slow client must not stall
    // the render.
    v1::JobState state;
    std::vector<std::pair<int, FrameRecord>> frames;
    v1::Progress progress;
    uint64_t progress_seq;
    std::string reason, code;
    int queue_pos;
    int final_before;  // final frames numbered below next_frame
    bool started;
    std::vector<int> skipped;
    {
      std::unique_lock<std::mutex> lock(mu_);
      state = job->state;
      auto first = job->final_frames.lower_bound(next_frame);
      final_before = int(std::distance(job->final_frames.begin(), first));
      for (auto it = first; it != job->final_frames.end(); ++it) frames.emplace_back(it->first, it->second);
      progress = job->progress;
      progress_seq = job->progress_seq;
      reason = job->reason;
      code = job->reason_code;
      queue_pos = queue_position_locked(*job);
      skipped = job->skipped;
      started = job->started_ms != 0;
    }
    v1::JobEvent ev;
    ev.set_job_id(job->id);
    if (state == v1::JOB_STATE_QUEUED && !queued_sent) {
      ev.mutable_queued()->set_queue_position(queue_pos);
      if (!send(ev)) return Status::Ok();
      queued_sent = true;
    }
    if (state != v1::JOB_STATE_QUEUED && !started_sent && started) {
      ev.Clear();
      ev.set_job_id(job->id);
      ev.mutable_started()->set_frames_total(progress.frames_total());
      for (int f : skipped) ev.mutable_started()->add_skipped_frames(f);
      if (!send(ev)) return Status::Ok();
      started_sent = true;
    }
    for (const auto& [f, rec] : frames) {
      // Each frame carries the count as of itself (frames become final in
      // frame order), not the snapshot's: a batch of frames solved together
      // must not all say "48/48" while 17 are still on their way.
      v1::Progress at_frame = progress;
      at_frame.set_frames_done(++final_before);
      at_frame.set_frames_rendered(std::max(at_frame.frames_rendered(), final_before));
      if (!send_frame(*job, f, rec, req.include_raw_rgb(), send, at_frame)) return Status::Ok();
      next_frame = f + 1;
    }
    if (is_terminal(state)) {
      ev.Clear();
      ev.set_job_id(job->id);
      if (state == v1::JOB_STATE_COMPLETED) *ev.mutable_completed()->mutable_progress() = progress;
      else if (state == v1::JOB_STATE_CANCELLED) ev.mutable_cancelled()->set_reason(client_text_(reason));
      else {
        ev.mutable_failed()->set_reason(client_text_(reason));
        ev.mutable_failed()->set_code(code);
      }
      (void)send(ev);
      return Status::Ok();
    }
    if (state == v1::JOB_STATE_RUNNING && progress_seq != progress_sent &&
        std::chrono::steady_clock::now() >= next_progress_at) {
      ev.Clear();
      ev.set_job_id(job->id);
      *ev.mutable_frame_rendered()->mutable_progress() = progress;
      if (!send(ev)) return Status::Ok();
      progress_sent = progress_seq;
      next_progress_at = std::chrono::steady_clock::now() + kProgressEventInterval;
    }
    // ---- Wait for news ----
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait_for(lock, std::chrono::milliseconds(500), [&] {
      if (stopping_ || job->state != state) return true;
      if (job->final_frames.lower_bound(next_frame) != job->final_frames.end()) return true;
      return job->progress_seq != progress_sent && std::chrono::steady_clock::now() >= next_progress_at;
    });
    if (stopping_) return Status(StatusCode::kUnavailable, "server is shutting down; watch again to resume");
    lock.unlock();
    if (client_gone()) return cancelled("client went away");
  }
}

}  // namespace gdvr::server
