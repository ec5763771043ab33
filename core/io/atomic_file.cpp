#include "core/io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace gdvr {

namespace {

std::string host_tag() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof(buf) - 1) != 0 || buf[0] == '\0') return "host";
  std::string h(buf);
  for (char& c : h)
    if (c == '/' || c == '.') c = '_';
  return h;
}

}  // namespace

std::string temporary_path_for(const std::string& path) {
  static const std::string tag = host_tag() + "." + std::to_string(static_cast<long>(::getpid()));
  return path + ".tmp." + tag;
}

Status write_text_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = temporary_path_for(path);
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return internal_error("cannot create '" + tmp + "': " + std::strerror(errno));
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !written) {
    discard_temporary(tmp);
    return internal_error("cannot write '" + tmp + "'");
  }
  return commit_temporary(tmp, path);
}

Status commit_temporary(const std::string& tmp, const std::string& path) {
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    discard_temporary(tmp);
    return internal_error("cannot rename '" + tmp + "' to '" + path + "': " + std::strerror(err));
  }
  return Status::Ok();
}

void discard_temporary(const std::string& tmp) { std::remove(tmp.c_str()); }

}  // namespace gdvr
