// The folder of uploaded scene bundles (<upload root>/<sha256>/...), kept
// apart from the operator's asset root. It enforces the quotas over all
// bundles together (files and bytes; an upload in progress reserves what it
// writes, so concurrent uploads cannot overshoot) and the retention of
// bundles that no queued or running job names. SceneBundleWriter
// (scene_upload.h) writes one bundle through it.
#pragma once

#include <cstdint>
#include <mutex>
#include <set>
#include <string>

#include "core/util/status.h"
#include "server/config.h"

namespace gdvr::server {

class UploadStore {
 public:
  explicit UploadStore(UploadPolicy policy) : policy_(std::move(policy)) {}

  // Creates the folder, deletes staging folders a killed server left, and
  // counts what the bundles hold.
  Status open();
  const std::string& root() const { return policy_.root; }
  // A fresh staging folder name inside the root (not created).
  std::string new_staging_dir() const;

  // Room for `bytes` and `files` more of an upload in progress, or
  // RESOURCE_EXHAUSTED naming the quota and its flag.
  Status reserve(uint64_t bytes, uint64_t files);
  void release(uint64_t bytes, uint64_t files);  // a failed or duplicate upload

  // Deletes every bundle whose last use (upload, or a job naming it) is older
  // than the retention and that `in_use` (hashes) does not hold. Returns how
  // many were deleted.
  int sweep(const std::set<std::string>& in_use);
  // Marks the bundle as used now (restarts its retention).
  void touch(const std::string& hash);

  uint64_t used_bytes() const;
  uint64_t used_files() const;

 private:
  UploadPolicy policy_;
  mutable std::mutex mu_;
  uint64_t used_bytes_ = 0, used_files_ = 0;
};

}  // namespace gdvr::server
