// Owns every job: the priority queue (FIFO within a priority), the workers
// that call run_job, per-frame persistence, and the event feed that WatchJob
// streams from. RPC handlers only translate to and from these calls.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <set>

#include "core/job/job_runner.h"
#include "gdvr/v1/render_service.pb.h"
#include "server/client_message.h"
#include "server/config.h"
#include "server/job_store.h"
#include "server/upload_store.h"

namespace gdvr::server {

class JobManager {
 public:
  // `uploads` (may be null: no uploaded scenes are touched) restarts a
  // bundle's retention when a job names it.
  JobManager(ServerConfig config, std::unique_ptr<JobStore> store, UploadStore* uploads = nullptr);
  ~JobManager();

  // Rebuilds the registry from the store; unfinished jobs go back to the
  // queue and will skip the frames already final.
  Status recover();
  void start();
  // No new work; running renders are cancelled and stay QUEUED in the store
  // (their final frames are already persisted), watchers are released. Joins.
  void shutdown();

  struct Submitted {
    v1::Job job;
    bool existing = false;
  };
  Expected<Submitted> submit(const std::string& idempotency_key, const v1::JobSpec& spec);
  Expected<v1::Job> get(const std::string& id) const;
  Expected<v1::ListJobsResponse> list(const v1::ListJobsRequest& request) const;
  // A queued job becomes CANCELLED; a running one CANCELLING (it stops at
  // the next tile, then is CANCELLED). Returns the job in that new state.
  Expected<v1::Job> cancel(const std::string& id);
  // The upload bundles (hashes) that queued or running jobs name: kept by
  // UploadStore::sweep whatever their age.
  std::set<std::string> uploads_in_use() const;

  // Streams the job's events through `send` (false: the client went away)
  // until it reaches a terminal state. `client_gone` is polled while idle.
  // A client leaving never affects the job.
  Status watch(const v1::WatchJobRequest& request, const std::function<bool(const v1::JobEvent&)>& send,
               const std::function<bool()>& client_gone);

  // Checks a spec against the server limits and core's validation. The
  // limits apply to what will be rendered: width, height and spp after the
  // scene file and the job's params resolve, and their product with the
  // frame count (--max-work). `core_job` comes back with its scene relative
  // to `scene_root` (the asset root, or an uploaded bundle's folder).
  Status validate(const v1::JobSpec& spec, JobSpec* core_job, std::vector<int>* frames,
                  std::string* scene_root = nullptr) const;
  // What clients see of an error text (server paths hidden, bounded).
  const ClientMessageFilter& client_text() const { return client_text_; }

  struct Artifact {
    std::string file;  // a plain name inside the job's folder
    v1::ArtifactKind kind;
  };
  // The job's output files that exist now, in a stable order (frames,
  // previews, video, stats); `kinds` empty: all.
  Expected<std::vector<Artifact>> artifacts(const std::string& id, const std::vector<v1::ArtifactKind>& kinds) const;
  std::string job_dir(const std::string& id) const;

 private:
  struct FrameRecord {
    std::string file;
    uint64_t size = 0;
    v1::FrameStats stats;
    int64_t final_us = 0;  // when it became final in this process; 0: before a restart
  };
  struct Job {
    std::string id, idempotency_key;
    v1::JobSpec spec;
    std::string spec_json;
    JobSpec core;            // its scene relative to scene_root
    std::string scene_root;  // the asset root, or the uploaded bundle's folder
    std::vector<int> frames;
    v1::JobState state = v1::JOB_STATE_QUEUED;
    int priority = 0;
    int64_t seq = 0;
    std::map<int, FrameRecord> final_frames;
    std::vector<int> skipped;  // final before this run started
    std::string reason, reason_code;
    int64_t created_ms = 0, started_ms = 0, finished_ms = 0;
    std::string video_file;  // set once the video is finished
    v1::Progress progress;
    uint64_t progress_seq = 0;
    std::atomic<bool> cancel{false};  // read by run_job once per tile
    bool cancel_requested = false;    // by a client, as opposed to shutdown
  };

  void worker_loop();
  Job* pick_next_locked();
  void run(Job* job);
  void finish_locked(Job* job, v1::JobState state, const std::string& reason, const std::string& code);
  void write_stats_json(const Job& job) const;  // call with mu_ held
  v1::Job to_proto_locked(const Job& job) const;
  int queue_position_locked(const Job& job) const;
  Status persist_state_locked(const Job& job);
  bool send_frame(const Job& job, int frame, const FrameRecord& rec, bool raw,
                  const std::function<bool(const v1::JobEvent&)>& send, const v1::Progress& progress);

  Status locate_core(Job* job);  // sets core.scene and scene_root from spec (recover)

  ServerConfig config_;
  std::unique_ptr<JobStore> store_;
  UploadStore* uploads_;
  ClientMessageFilter client_text_;
  mutable std::mutex mu_;
  std::condition_variable cv_;  // any job change; workers and watchers wait on it
  std::map<std::string, std::unique_ptr<Job>> jobs_;
  std::map<std::string, std::string> by_key_;  // idempotency key -> job id
  int64_t next_seq_ = 1;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace gdvr::server
