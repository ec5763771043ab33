// Reassembles streamed frame chunks and saves each final frame atomically as
// <dir>/frame_0001.exr, so a folder only ever holds complete frames and a
// resumed watch can start after the last one.
#pragma once

#include <map>
#include <string>

#include "gdvr/v1/render_service.pb.h"

namespace gdvr::client {

class FrameSink {
 public:
  explicit FrameSink(std::string dir) : dir_(std::move(dir)) {}
  // Returns false (with `error`) on an out-of-order chunk or a write failure.
  // `completed_frame` is set to the frame number when its last chunk arrived.
  bool add(const v1::FrameFinal& chunk, int* completed_frame, std::string* error);

  // The frame to resume from: one past the highest frame_NNNN.exr in `dir`
  // (frames arrive in order, so the files present form a prefix); -1: none.
  static int resume_frame(const std::string& dir);

 private:
  std::string dir_;
  int frame_ = -1;
  std::string exr_;
};

}  // namespace gdvr::client
