// Which sample streams the two half passes of a T-GPT frame use
// (Manzi et al. 2016, public release; docs/tgpt.md): frame t renders pass A
// with stream s(t) and pass B with stream s(t_next), t_next the next frame of
// the job, so pass B of frame t and pass A of frame t_next replay the same
// random numbers (Sampler(seed, stream, px, py, s), core/math/rng.h) in two
// consecutive scene states. dt_t = A_{t_next} − B_t is then a correlated
// difference: no MIS and no Jacobian, because it is a replay.
#pragma once

#include <cstdint>
#include <vector>

namespace gdvr {

struct TgptPassStreams {
  uint32_t a = 0;  // stream of pass A (shared with pass B of the previous frame)
  uint32_t b = 0;  // stream of pass B (shared with pass A of the next frame)
};

// s(t) = t: pass A of frame t uses the same stream G-PT would use for frame t.
inline uint32_t tgpt_stream(int frame) { return uint32_t(frame); }

// Streams of the frame at `index` in the job's (sorted) frame list. The last
// frame's pass B uses s(t + 1), as if the shot went on.
inline TgptPassStreams tgpt_pass_streams(const std::vector<int>& job_frames, size_t index) {
  const int t = job_frames[index];
  const int next = index + 1 < job_frames.size() ? job_frames[index + 1] : t + 1;
  return {tgpt_stream(t), tgpt_stream(next)};
}

// Samples per pixel of each half pass: both passes take the same count, so
// that B_t and A_{t_next} stay sample-by-sample correlated; an odd job spp is
// rounded up (the frame then takes spp + 1).
inline int tgpt_pass_spp(int job_spp) { return job_spp <= 1 ? 1 : (job_spp + 1) / 2; }

}  // namespace gdvr
