#include "client/frame_sink.h"

#include <climits>
#include <filesystem>
#include <fstream>

namespace gdvr::client {
namespace fs = std::filesystem;

bool FrameSink::add(const v1::FrameFinal& c, int* completed_frame, std::string* error) {
  *completed_frame = INT_MIN;
  if (c.offset() == 0 && c.payload() == v1::FrameFinal::PAYLOAD_EXR) {
    frame_ = c.frame();
    exr_.clear();
    exr_.reserve(c.total_size());
  }
  if (c.frame() != frame_) {
    *error = "chunk of frame " + std::to_string(c.frame()) + " arrived while frame " + std::to_string(frame_) +
             " was incomplete";
    return false;
  }
  if (c.payload() == v1::FrameFinal::PAYLOAD_EXR) {
    if (c.offset() != exr_.size()) {
      *error = "frame " + std::to_string(frame_) + ": chunk at offset " + std::to_string(c.offset()) + ", expected " +
               std::to_string(exr_.size());
      return false;
    }
    exr_ += c.data();
  }
  if (!c.last()) return true;
  if (exr_.size() != c.total_size() && c.payload() == v1::FrameFinal::PAYLOAD_EXR) {
    *error = "frame " + std::to_string(frame_) + ": got " + std::to_string(exr_.size()) + " of " +
             std::to_string(c.total_size()) + " bytes";
    return false;
  }
  if (!dir_.empty()) {
    std::error_code ec;
    fs::create_directories(dir_, ec);
    std::string name = c.file_name().empty() ? "frame_" + std::to_string(frame_) + ".exr" : c.file_name();
    if (name.find('/') != std::string::npos || name == ".." || name == ".") {
      *error = "server sent an unsafe file name '" + name + "'";
      return false;
    }
    fs::path path = fs::path(dir_) / name, tmp = path;
    tmp += ".part";
    {
      std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
      out.write(exr_.data(), std::streamsize(exr_.size()));
      if (!out) {
        *error = "cannot write " + tmp.string();
        return false;
      }
    }
    fs::rename(tmp, path, ec);
    if (ec) {
      *error = "cannot rename " + tmp.string() + ": " + ec.message();
      return false;
    }
  }
  *completed_frame = frame_;
  frame_ = -1;
  exr_.clear();
  return true;
}

int FrameSink::resume_frame(const std::string& dir) {
  std::error_code ec;
  int best = INT_MIN;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::string n = e.path().filename().string();
    if (n.rfind("frame_", 0) != 0 || n.size() < 11 || n.substr(n.size() - 4) != ".exr") continue;
    try {
      best = std::max(best, std::stoi(n.substr(6, n.size() - 10)));
    } catch (...) {
    }
  }
  return best == INT_MIN ? -1 : best + 1;
}

}  // namespace gdvr::client
