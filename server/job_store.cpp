#include "server/job_store.h"

#include <sqlite3.h>

namespace gdvr::server {
namespace {

// Owns a prepared statement; binds by 1-based index.
class Stmt {
 public:
  Stmt(sqlite3* db, const char* sql) : db_(db) { rc_ = sqlite3_prepare_v2(db, sql, -1, &st_, nullptr); }
  ~Stmt() { sqlite3_finalize(st_); }
  bool ok() const { return rc_ == SQLITE_OK; }
  Stmt& bind(int i, const std::string& v) {
    sqlite3_bind_text(st_, i, v.data(), int(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Stmt& bind_blob(int i, const std::string& v) {
    sqlite3_bind_blob(st_, i, v.data(), int(v.size()), SQLITE_TRANSIENT);
    return *this;
  }
  Stmt& bind_null(int i) {
    sqlite3_bind_null(st_, i);
    return *this;
  }
  Stmt& bind(int i, int64_t v) {
    sqlite3_bind_int64(st_, i, v);
    return *this;
  }
  int step() { return sqlite3_step(st_); }
  std::string text(int col) {
    auto* p = reinterpret_cast<const char*>(sqlite3_column_blob(st_, col));
    return p ? std::string(p, size_t(sqlite3_column_bytes(st_, col))) : std::string();
  }
  int64_t integer(int col) { return sqlite3_column_int64(st_, col); }
  Status error(const char* what) const { return internal_error(std::string(what) + ": " + sqlite3_errmsg(db_)); }

 private:
  sqlite3* db_;
  sqlite3_stmt* st_ = nullptr;
  int rc_;
};

}  // namespace

Expected<std::unique_ptr<JobStore>> JobStore::open(const std::string& path) {
  sqlite3* db = nullptr;
  int rc = sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                           nullptr);
  if (rc != SQLITE_OK) {
    std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    return internal_error("--db: cannot open '" + path + "': " + msg);
  }
  std::unique_ptr<JobStore> store(new JobStore(db));
  sqlite3_busy_timeout(db, 5000);
  // WAL: readers never block the writer, and a kill -9 loses at most the
  // transaction in flight. synchronous=NORMAL is durable across process
  // crashes (not power loss), which is what restart safety needs.
  GDVR_RETURN_IF_ERROR(store->exec("PRAGMA journal_mode=WAL"));
  GDVR_RETURN_IF_ERROR(store->exec("PRAGMA synchronous=NORMAL"));
  GDVR_RETURN_IF_ERROR(store->exec("PRAGMA foreign_keys=ON"));
  GDVR_RETURN_IF_ERROR(store->migrate());
  return store;
}

JobStore::~JobStore() { sqlite3_close(db_); }

Status JobStore::exec(const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    std::string msg = err ? err : "unknown error";
    sqlite3_free(err);
    return internal_error("sqlite: " + msg + " in: " + sql.substr(0, 60));
  }
  return Status::Ok();
}

Status JobStore::migrate() {
  std::lock_guard<std::mutex> lock(mu_);
  GDVR_RETURN_IF_ERROR(exec("CREATE TABLE IF NOT EXISTS schema_version(version INTEGER NOT NULL)"));
  int64_t version = 0;
  {
    Stmt st(db_, "SELECT MAX(version) FROM schema_version");
    if (!st.ok()) return st.error("schema_version");
    if (st.step() == SQLITE_ROW) version = st.integer(0);
  }
  if (version > kSchemaVersion)
    return failed_precondition("--db: schema version " + std::to_string(version) +
                               " is newer than this server's (" + std::to_string(kSchemaVersion) + ")");
  if (version < 1) {
    GDVR_RETURN_IF_ERROR(exec("BEGIN"));
    Status st = exec(R"(
      CREATE TABLE jobs(
        id TEXT PRIMARY KEY,
        idempotency_key TEXT UNIQUE,
        seq INTEGER NOT NULL,
        priority INTEGER NOT NULL,
        state INTEGER NOT NULL,
        spec_json TEXT NOT NULL,
        reason TEXT NOT NULL DEFAULT '',
        reason_code TEXT NOT NULL DEFAULT '',
        created_ms INTEGER NOT NULL,
        started_ms INTEGER NOT NULL DEFAULT 0,
        finished_ms INTEGER NOT NULL DEFAULT 0);
      CREATE TABLE frames(
        job_id TEXT NOT NULL REFERENCES jobs(id),
        frame INTEGER NOT NULL,
        file TEXT NOT NULL,
        size INTEGER NOT NULL,
        stats BLOB,
        PRIMARY KEY(job_id, frame));
      INSERT INTO schema_version(version) VALUES (1);)");
    if (!st.ok()) {
      (void)exec("ROLLBACK");
      return st;
    }
    GDVR_RETURN_IF_ERROR(exec("COMMIT"));
  }
  return Status::Ok();
}

Status JobStore::insert_job(const StoredJob& j) {
  std::lock_guard<std::mutex> lock(mu_);
  Stmt st(db_, "INSERT INTO jobs(id, idempotency_key, seq, priority, state, spec_json, created_ms) "
               "VALUES(?,?,?,?,?,?,?)");
  if (!st.ok()) return st.error("insert job");
  st.bind(1, j.id);
  // NULL, not '', for "no key": UNIQUE allows any number of NULLs.
  if (j.idempotency_key.empty()) st.bind_null(2);
  else st.bind(2, j.idempotency_key);
  st.bind(3, j.seq).bind(4, int64_t(j.priority)).bind(5, int64_t(j.state));
  st.bind(6, j.spec_json).bind(7, j.created_ms);
  if (st.step() != SQLITE_DONE) return st.error("insert job");
  return Status::Ok();
}

Status JobStore::update_job(const std::string& id, int state, const std::string& reason,
                            const std::string& reason_code, int64_t started_ms, int64_t finished_ms) {
  std::lock_guard<std::mutex> lock(mu_);
  Stmt st(db_, "UPDATE jobs SET state=?, reason=?, reason_code=?, started_ms=?, finished_ms=? WHERE id=?");
  if (!st.ok()) return st.error("update job");
  st.bind(1, int64_t(state)).bind(2, reason).bind(3, reason_code).bind(4, started_ms).bind(5, finished_ms);
  st.bind(6, id);
  if (st.step() != SQLITE_DONE) return st.error("update job");
  return Status::Ok();
}

Status JobStore::insert_frame(const std::string& job_id, const StoredFrame& f) {
  std::lock_guard<std::mutex> lock(mu_);
  Stmt st(db_, "INSERT OR REPLACE INTO frames(job_id, frame, file, size, stats) VALUES(?,?,?,?,?)");
  if (!st.ok()) return st.error("insert frame");
  st.bind(1, job_id).bind(2, int64_t(f.frame)).bind(3, f.file).bind(4, int64_t(f.size)).bind_blob(5, f.stats_pb);
  if (st.step() != SQLITE_DONE) return st.error("insert frame");
  return Status::Ok();
}

Expected<std::vector<StoredJob>> JobStore::load_all() {
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<StoredJob> jobs;
  {
    Stmt st(db_, "SELECT id, COALESCE(idempotency_key, ''), seq, priority, state, spec_json, reason, reason_code, "
                 "created_ms, started_ms, finished_ms FROM jobs ORDER BY seq");
    if (!st.ok()) return st.error("load jobs");
    int rc;
    while ((rc = st.step()) == SQLITE_ROW) {
      StoredJob j;
      j.id = st.text(0);
      j.idempotency_key = st.text(1);
      j.seq = st.integer(2);
      j.priority = int(st.integer(3));
      j.state = int(st.integer(4));
      j.spec_json = st.text(5);
      j.reason = st.text(6);
      j.reason_code = st.text(7);
      j.created_ms = st.integer(8);
      j.started_ms = st.integer(9);
      j.finished_ms = st.integer(10);
      jobs.push_back(std::move(j));
    }
    if (rc != SQLITE_DONE) return st.error("load jobs");
  }
  for (auto& j : jobs) {
    Stmt fs(db_, "SELECT frame, file, size, stats FROM frames WHERE job_id=? ORDER BY frame");
    fs.bind(1, j.id);
    int rc;
    while ((rc = fs.step()) == SQLITE_ROW) {
      StoredFrame f;
      f.frame = int(fs.integer(0));
      f.file = fs.text(1);
      f.size = uint64_t(fs.integer(2));
      f.stats_pb = fs.text(3);
      j.frames.push_back(std::move(f));
    }
    if (rc != SQLITE_DONE) return fs.error("load frames");
  }
  return jobs;
}

}  // namespace gdvr::server
