// The folder the two farm stages share: per frame, the render stage's
// buffers (every pre-reconstruction layer, float EXR) and a JSON marker
// written after them (its FrameStats and the job's fingerprint), so a frame
// counts as rendered only once both are in place and agree; and, per
// finalized frame, its stats.json entry.
#pragma once

#include <string>

#include "core/farm/farm_job.h"
#include "core/job/job_runner.h"
#include "core/util/status.h"

namespace gdvr::farm {

std::string buffers_exr_name(int frame);   // buffers_0001.exr
std::string buffers_json_name(int frame);  // buffers_0001.json, the marker
// A finalized frame's stats.json entry, kept beside the buffers (which every
// task shares) so the last finalize lists the whole job's frames.
std::string final_stats_name(int frame);   // final_0001.json

enum class BufferState { kMissing, kComplete, kForeign };

struct BufferCheck {
  BufferState state = BufferState::kMissing;
  FrameStats stats;  // kComplete: the render stage's statistics
  std::string why;   // kMissing/kForeign: what is wrong
};

// A frame's buffers are complete when its JSON marker parses, names this
// job's fingerprint and the EXR beside it has the size the marker recorded
// (a file copied in half, or replaced by hand, does not pass).
BufferCheck check_buffers(const FarmJob& job, const std::string& dir, int frame);

// The buffers first, the marker last: a worker killed between the two leaves
// a frame that counts as not rendered, and the retry writes it again.
Status write_buffers(const FarmJob& job, const std::string& dir, const FrameBuffers& buffers);

// A frame's buffers for finalizing `for_frame` (itself or a frame whose
// window needs it): NOT_FOUND when missing (the message says how to render
// them), FAILED_PRECONDITION when they belong to another job.
Expected<FrameBuffers> read_buffers(const FarmJob& job, const std::string& dir, int frame, int for_frame);
// The same buffers left in their EXR (FrameBuffers::on_disk, `layers` empty):
// only the header is read now, and each region the finalize asks for later is
// read then, decompressing only its rows. A tile task (finalize --tiles) reads
// so only its tiles' part of each window frame, not every frame whole.
Expected<FrameBuffers> open_buffers(const FarmJob& job, const std::string& dir, int frame, int for_frame);

// stats.json in the output folder, as gdvr-render and the server write it:
// every frame of the job that is final there (by this task or an earlier
// one) with its statistics. Tasks finalizing chunks in parallel each write
// what they see; the last one to finish lists all.
Status write_job_stats(const FarmJob& job, const std::string& buffers_dir, const std::string& out_dir);

}  // namespace gdvr::farm
