// Receives a scene bundle (scene file plus assets) into the upload folder,
// <upload root>/<sha256>/ (upload_store.h), content-addressed so that
// uploading the same bundle twice is free and jobs can name it by hash.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>

#include "core/util/status.h"
#include "server/upload_store.h"

namespace gdvr::server {

struct UploadedBundle {
  std::string hash;   // hex SHA-256
  std::string scene;  // what a job names: "uploads/<hash>/scene.xml"
  uint64_t total_bytes = 0;
  int files = 0;
};

class SceneBundleWriter {
 public:
  // `max_bytes`: this bundle's limit (--max-upload-bytes); the store's quotas
  // bound all bundles together.
  SceneBundleWriter(UploadStore* store, uint64_t max_bytes);
  ~SceneBundleWriter();  // removes the staging folder and its reservation unless finish() succeeded

  // Appends `data` to `path` (a new path closes the previous file).
  Status add(const std::string& scene_file, const std::string& path, const std::string& data);
  Expected<UploadedBundle> finish();

 private:
  UploadStore* store_;
  std::string staging_, scene_file_, current_;
  uint64_t max_bytes_, total_ = 0;
  uint64_t reserved_bytes_ = 0, reserved_files_ = 0;
  std::map<std::string, uint64_t> files_;  // sorted: the hash is order-independent
  std::ofstream out_;
  bool done_ = false;
};

// Rejects absolute paths, "..", empty or odd components, components longer
// than a file name can be (all INVALID_ARGUMENT, naming the path).
Status check_bundle_path(const std::string& path);

}  // namespace gdvr::server
