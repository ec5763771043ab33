#include "server/upload_store.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>

#include "server/log.h"
#include "server/scene_location.h"

namespace gdvr::server {
namespace fs = std::filesystem;

namespace {

constexpr const char* kStagingPrefix = ".incoming-";

struct Usage {
  uint64_t bytes = 0, files = 0;
};

Usage measure(const fs::path& dir) {
  Usage u;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    ++u.files;
    u.bytes += uint64_t(it->file_size(ec));
  }
  return u;
}

}  // namespace

Status UploadStore::open() {
  std::error_code ec;
  fs::create_directories(policy_.root, ec);
  if (ec) return internal_error("--upload-root: cannot create '" + policy_.root + "': " + ec.message());
  Usage total;
  for (const auto& e : fs::directory_iterator(policy_.root, ec)) {
    std::string name = e.path().filename().string();
    if (name.rfind(kStagingPrefix, 0) == 0) {
      fs::remove_all(e.path(), ec);  // an upload a killed server never finished
      continue;
    }
    Usage u = measure(e.path());
    total.bytes += u.bytes;
    total.files += u.files;
  }
  std::lock_guard<std::mutex> lock(mu_);
  used_bytes_ = total.bytes;
  used_files_ = total.files;
  return Status::Ok();
}

std::string UploadStore::new_staging_dir() const {
  std::random_device rd;
  char buf[48];
  std::snprintf(buf, sizeof buf, "%s%08x%08x", kStagingPrefix, rd(), rd());
  return (fs::path(policy_.root) / buf).string();
}

Status UploadStore::reserve(uint64_t bytes, uint64_t files) {
  std::lock_guard<std::mutex> lock(mu_);
  if (used_files_ + files > policy_.quota_files)
    return resource_exhausted("upload: the server's upload folder is full: it holds " + std::to_string(used_files_) +
                              " files of its quota of " + std::to_string(policy_.quota_files) +
                              " (--upload-quota-files); bundles no job needs are deleted after " +
                              std::to_string(int64_t(policy_.retention_s)) + " s (--upload-retention-s)");
  if (used_bytes_ + bytes > policy_.quota_bytes)
    return resource_exhausted("upload: the server's upload folder is full: it holds " + std::to_string(used_bytes_) +
                              " bytes of its quota of " + std::to_string(policy_.quota_bytes) +
                              " (--upload-quota-bytes); bundles no job needs are deleted after " +
                              std::to_string(int64_t(policy_.retention_s)) + " s (--upload-retention-s)");
  used_bytes_ += bytes;
  used_files_ += files;
  return Status::Ok();
}

void UploadStore::release(uint64_t bytes, uint64_t files) {
  std::lock_guard<std::mutex> lock(mu_);
  used_bytes_ -= std::min(used_bytes_, bytes);
  used_files_ -= std::min(used_files_, files);
}

int UploadStore::sweep(const std::set<std::string>& in_use) {
  const auto now = fs::file_time_type::clock::now();
  const auto retention = std::chrono::duration_cast<fs::file_time_type::duration>(
      std::chrono::duration<double>(policy_.retention_s));
  int deleted = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(policy_.root, ec)) {
    std::string hash = e.path().filename().string();
    if (!is_bundle_hash(hash) || in_use.count(hash)) continue;
    std::error_code tec;
    auto last_use = fs::last_write_time(e.path(), tec);
    if (tec || now - last_use < retention) continue;
    Usage u = measure(e.path());
    std::error_code rec;
    fs::remove_all(e.path(), rec);
    if (rec) {
      log_event("warn", "upload_sweep_failed", {{"bundle", hash}, {"error", rec.message()}});
      continue;
    }
    release(u.bytes, u.files);
    ++deleted;
    log_event("info", "upload_expired", {{"bundle", hash}, {"bytes", std::to_string(u.bytes)},
                                         {"files", std::to_string(u.files)}});
  }
  return deleted;
}

void UploadStore::touch(const std::string& hash) {
  if (!is_bundle_hash(hash)) return;
  std::error_code ec;
  fs::last_write_time(fs::path(policy_.root) / hash, fs::file_time_type::clock::now(), ec);
}

uint64_t UploadStore::used_bytes() const {
  std::lock_guard<std::mutex> lock(mu_);
  return used_bytes_;
}

uint64_t UploadStore::used_files() const {
  std::lock_guard<std::mutex> lock(mu_);
  return used_files_;
}

}  // namespace gdvr::server
