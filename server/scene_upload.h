// Receives a scene bundle (scene file plus assets) into
// <asset_root>/uploads/<sha256>/, content-addressed so that uploading the same
// bundle twice is free and jobs can name it by hash.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>

#include "core/util/status.h"

namespace gdvr::server {

struct UploadedBundle {
  std::string hash;   // hex SHA-256
  std::string scene;  // asset-root-relative, e.g. "uploads/<hash>/scene.xml"
  uint64_t total_bytes = 0;
  int files = 0;
};

class SceneBundleWriter {
 public:
  SceneBundleWriter(std::string asset_root, uint64_t max_bytes);
  ~SceneBundleWriter();  // removes the staging folder unless finish() succeeded

  // Appends `data` to `path` (a new path closes the previous file).
  Status add(const std::string& scene_file, const std::string& path, const std::string& data);
  Expected<UploadedBundle> finish();

 private:
  std::string asset_root_, staging_, scene_file_, current_;
  uint64_t max_bytes_, total_ = 0;
  std::map<std::string, uint64_t> files_;  // sorted: the hash is order-independent
  std::ofstream out_;
  bool done_ = false;
};

// Rejects absolute paths, "..", empty or odd components (named in the message).
Status check_bundle_path(const std::string& path);

}  // namespace gdvr::server
