#include "server/scene_upload.h"

#include <openssl/evp.h>

#include <filesystem>
#include <vector>

#include "core/util/echo_text.h"
#include "server/scene_location.h"

namespace gdvr::server {
namespace fs = std::filesystem;

Status check_bundle_path(const std::string& path) {
  if (path.empty()) return invalid_argument("path: empty file name in the bundle");
  const std::string shown = "path: '" + echo_text(path) + "'";
  if (path.size() > 512) return invalid_argument(shown + " is longer than 512 characters");
  if (path[0] == '/' || path.find('\\') != std::string::npos || path.find(':') != std::string::npos)
    return invalid_argument(shown + " must be relative and '/'-separated");
  size_t start = 0;
  while (start <= path.size()) {
    size_t end = path.find('/', start);
    if (end == std::string::npos) end = path.size();
    std::string part = path.substr(start, end - start);
    if (part.empty() || part == "." || part == "..")
      return invalid_argument(shown + " has an empty, '.' or '..' component");
    // NAME_MAX: such a file cannot be written, and that is the request's
    // fault, not the server's.
    if (part.size() > 255) return invalid_argument(shown + " has a component longer than 255 bytes");
    for (unsigned char c : part)
      if (c < 0x20 || c == 0x7f) return invalid_argument(shown + " has a control character");
    start = end + 1;
  }
  return Status::Ok();
}

SceneBundleWriter::SceneBundleWriter(UploadStore* store, uint64_t max_bytes)
    : store_(store), staging_(store->new_staging_dir()), max_bytes_(max_bytes) {}

SceneBundleWriter::~SceneBundleWriter() {
  out_.close();
  if (!done_) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
    store_->release(reserved_bytes_, reserved_files_);
  }
}

Status SceneBundleWriter::add(const std::string& scene_file, const std::string& path, const std::string& data) {
  if (!scene_file.empty()) {
    if (!scene_file_.empty() && scene_file != scene_file_)
      return invalid_argument("scene_file: changed from '" + echo_text(scene_file_) + "' to '" + echo_text(scene_file) +
                              "' mid-upload");
    scene_file_ = scene_file;
  }
  if (path.empty() && data.empty()) return Status::Ok();
  std::string p = path.empty() ? current_ : path;
  if (p.empty()) return invalid_argument("path: the first chunk with data must name its file");
  if (p != current_) {
    GDVR_RETURN_IF_ERROR(check_bundle_path(p));
    if (files_.count(p))
      return invalid_argument("path: '" + echo_text(p) + "' sent twice (send each file's chunks together)");
    // "a" and "a/b" cannot both be files.
    for (const auto& [f, size] : files_) {
      if (p.compare(0, f.size() + 1, f + "/") == 0 || f.compare(0, p.size() + 1, p + "/") == 0)
        return invalid_argument("path: '" + echo_text(p) + "' and '" + echo_text(f) +
                                "' cannot both be in a bundle (one would be a file and a folder)");
    }
    GDVR_RETURN_IF_ERROR(store_->reserve(0, 1));
    ++reserved_files_;
    out_.close();
    fs::path target = fs::path(staging_) / p;
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    out_.open(target, std::ios::binary | std::ios::trunc);
    if (!out_) return internal_error("upload: cannot write the staging file for '" + echo_text(p) + "' under " + staging_);
    current_ = p;
    files_[p] = 0;
  }
  total_ += data.size();
  if (total_ > max_bytes_)
    return resource_exhausted("upload: bundle exceeds the server limit of " + std::to_string(max_bytes_) +
                              " bytes (--max-upload-bytes)");
  GDVR_RETURN_IF_ERROR(store_->reserve(data.size(), 0));
  reserved_bytes_ += data.size();
  out_.write(data.data(), std::streamsize(data.size()));
  if (!out_) return internal_error("upload: write failed for '" + echo_text(p) + "' under " + staging_);
  files_[p] += data.size();
  return Status::Ok();
}

Expected<UploadedBundle> SceneBundleWriter::finish() {
  out_.close();
  if (scene_file_.empty()) return invalid_argument("scene_file: missing (name the bundle's scene .xml)");
  if (!files_.count(scene_file_))
    return invalid_argument("scene_file: '" + echo_text(scene_file_) + "' is not in the bundle");
  // SHA-256 over (path, NUL, size, NUL, bytes) of every file in path order.
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> md(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  EVP_DigestInit_ex(md.get(), EVP_sha256(), nullptr);
  std::vector<char> buf(1 << 16);
  for (const auto& [path, size] : files_) {
    std::string head = path + '\0' + std::to_string(size) + '\0';
    EVP_DigestUpdate(md.get(), head.data(), head.size());
    std::ifstream in(fs::path(staging_) / path, std::ios::binary);
    while (in) {
      in.read(buf.data(), std::streamsize(buf.size()));
      EVP_DigestUpdate(md.get(), buf.data(), size_t(in.gcount()));
    }
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_DigestFinal_ex(md.get(), digest, &len);
  std::string hex;
  static const char* kHex = "0123456789abcdef";
  for (unsigned i = 0; i < len; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  std::string final_dir = (fs::path(store_->root()) / hex).string();
  std::error_code ec;
  if (fs::exists(final_dir, ec)) {
    // Same content already there: it counts once, and its retention restarts.
    fs::remove_all(staging_, ec);
    store_->release(reserved_bytes_, reserved_files_);
    store_->touch(hex);
  } else {
    fs::rename(staging_, final_dir, ec);
    if (ec) return internal_error("upload: cannot move the bundle into " + final_dir + ": " + ec.message());
  }
  done_ = true;
  return UploadedBundle{hex, std::string(kUploadScenePrefix) + hex + "/" + scene_file_, total_, int(files_.size())};
}

}  // namespace gdvr::server
