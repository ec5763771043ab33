// SQLite persistence of jobs and per-frame state (WAL, versioned schema). The
// store is the source of truth across restarts; the in-memory registry in
// JobManager is rebuilt from it on start-up.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/util/status.h"

struct sqlite3;

namespace gdvr::server {

struct StoredFrame {
  int frame = 0;
  std::string file;      // name within the job's output folder
  uint64_t size = 0;     // bytes of the EXR
  std::string stats_pb;  // serialized gdvr.v1.FrameStats
};

struct StoredJob {
  std::string id;
  std::string idempotency_key;
  int64_t seq = 0;  // submission order: FIFO within a priority
  int priority = 0;
  int state = 0;    // gdvr.v1.JobState
  std::string spec_json;
  std::string reason, reason_code;
  int64_t created_ms = 0, started_ms = 0, finished_ms = 0;
  std::vector<StoredFrame> frames;  // final frames, ascending
};

class JobStore {
 public:
  static constexpr int kSchemaVersion = 1;

  static Expected<std::unique_ptr<JobStore>> open(const std::string& path);
  ~JobStore();
  JobStore(const JobStore&) = delete;
  JobStore& operator=(const JobStore&) = delete;

  Status insert_job(const StoredJob& job);
  Status update_job(const std::string& id, int state, const std::string& reason, const std::string& reason_code,
                    int64_t started_ms, int64_t finished_ms);
  // Idempotent: re-recording a frame (after a crash between the rename and the
  // insert) replaces the row.
  Status insert_frame(const std::string& job_id, const StoredFrame& frame);
  Expected<std::vector<StoredJob>> load_all();

 private:
  explicit JobStore(sqlite3* db) : db_(db) {}
  Status exec(const std::string& sql);
  Status migrate();

  std::mutex mu_;  // one connection shared by RPC and worker threads
  sqlite3* db_ = nullptr;
};

}  // namespace gdvr::server
