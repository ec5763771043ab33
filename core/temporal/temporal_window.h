// Stage 2 of T-GPT: the sliding-window reconstruction of a shot from its
// frames' buffers (Manzi et al. 2016; docs/tgpt.md, "Reconstruction: sliding windows").
//
// The windows are those of core/recon's SlidingWindowReconstructor (W frames,
// hop H = W/2 by default, Hann blend ½(1 + cos(2π(f − c)/W)) normalised by the
// weights' sum, the last window clamped to the shot, a shot shorter than W is
// one window), but as a pure function of (shot length, W, H) so that any frame
// can be finalized on its own from the buffers of the windows containing it —
// a farm finalizes frames in separate processes — and give the same image as
// the in-process streaming run, which solves each window once (the cache).
#pragma once

#include <functional>
#include <map>
#include <vector>

#include "core/image/image.h"
#include "core/recon/recon_result.h"
#include "core/temporal/tgpt_settings.h"

namespace gdvr {

struct WindowRange {
  int start = 0, end = 0;  // shot positions [start, end)
};

// All windows of a shot of `frame_count` frames, in solve order.
std::vector<WindowRange> shot_windows(int frame_count, int window, int hop);
// Positions whose buffers finalizing position `index` needs: the frames of
// every window containing it, plus index + 1 (its own dt layer), clamped to the shot.
std::vector<int> positions_needed(int frame_count, int window, int hop, int index);

// Buffers of the frame at a shot position (nullptr if not available).
using ShotLayers = std::function<const LayeredImage*(int index)>;

class TemporalWindowCache {
 public:
  TemporalWindowCache(TgptSettings settings, int frame_count);

  // The reconstructed indirect image (without "direct") of shot position
  // `index`: the Hann blend of the solutions of all windows containing it.
  // Solves (and keeps) the windows not solved yet.
  Expected<Image> reconstruct(int index, const ShotLayers& layers, ReconStats* stats);
  // Frees the solutions of windows that end at or before `index`.
  void release_before(int index);
  // Whether the buffers of shot position `position` are still read once every
  // position before `first_unfinalized` is out: by a frame not out yet (itself,
  // or as the successor of its dt layer), or by a window containing such a
  // frame that is not solved yet. Solved windows keep their solutions, so the
  // streaming run holds about W frames of buffers instead of W + H.
  bool buffers_needed(int position, int first_unfinalized) const;
  int windows_solved() const { return windows_solved_; }
  int cached_windows() const { return int(solved_.size()); }

 private:
  Status solve(const WindowRange& w, const ShotLayers& layers, ReconStats* stats);

  TgptSettings settings_;
  int frame_count_;
  std::vector<WindowRange> windows_;
  std::map<int, std::vector<Image>> solved_;  // by window index
  int windows_solved_ = 0;
};

}  // namespace gdvr
