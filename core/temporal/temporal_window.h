// Stage 2 of T-GPT: the sliding-window reconstruction of a shot from its
// frames' buffers (Manzi et al. 2016; docs/tgpt.md, "Reconstruction: sliding
// windows"), and the schedule that goes with it: which frames' buffers a frame
// needs, and when held buffers and solved windows can go.
//
// Windows of W frames start every H frames (H = W/2 by default, the public
// T-GPT code's 50 % overlap); the shot's last window is clamped to the shot,
// and a shot shorter than W is one window. A frame is the blend of the
// solutions of all windows containing it with Hann weights
// ½(1 + cos(2π(f − c)/W)), c the window's centre, normalised by their sum:
// with H = W/2 every frame lies in two windows whose weights sum to one, and
// a window's seams (where its solve lacks the constraints beyond its border)
// get a weight near zero.
//
// The schedule is a pure function of (shot length, W, H), so that any frame
// can be finalized on its own from the buffers of the windows containing it
// (a farm finalizes frames in separate processes) and give the same image as
// the in-process streaming run, which solves each window once (the cache).
#pragma once

#include <functional>
#include <map>
#include <vector>

#include "core/image/image.h"
#include "core/recon/gradient_window.h"
#include "core/recon/recon_result.h"
#include "core/temporal/tgpt_settings.h"

namespace gdvr {

struct WindowRange {
  int start = 0, end = 0;  // shot positions [start, end)
};

// All windows of a shot of `frame_count` frames, in solve order (hop 0: W/2).
std::vector<WindowRange> shot_windows(int frame_count, int window, int hop);
// Positions whose buffers finalizing position `index` needs: the frames of
// every window containing it, plus index + 1 (its own dt layer), clamped to the shot.
std::vector<int> positions_needed(int frame_count, int window, int hop, int index);
// Hann weight of shot position `index` in the window starting at `start`
// with nominal size `window` (> 0 everywhere inside the window).
double window_blend_weight(int index, int start, int window);

// Solves one window: one image per frame of the window, and the solve's numbers.
using WindowSolver = std::function<Expected<ReconResult>(const GradientWindow&)>;

// The windows of one shot in the job's frame numbers, each solved at most once
// while a frame still to come needs it.
class TemporalWindowCache {
 public:
  // `frames`: the shot's frame numbers, ascending (a job's frame range).
  // `solve`: by default reconstruct(window, settings.recon).
  TemporalWindowCache(TgptSettings settings, std::vector<int> frames, WindowSolver solve = {});

  const std::vector<int>& frames() const { return frames_; }
  // Index of `frame` in frames(), -1 if the shot lacks it.
  int position(int frame) const;
  // The frames whose buffers finalizing `frame` reads: every frame of every
  // window containing it, and the next frame (its own dt layer), ascending.
  std::vector<int> frames_needed(int frame) const;

  // Buffers of a frame of the shot (nullptr if not available).
  using FrameLayers = std::function<const LayeredImage*(int frame)>;
  // The reconstructed indirect image (without "direct") of `frame`: the Hann
  // blend of the solutions of all windows containing it. Solves (and keeps)
  // the windows not solved yet.
  Expected<Image> reconstruct(int frame, const FrameLayers& layers, ReconStats* stats);
  // Frees the solutions of windows whose last frame is `frame` or earlier:
  // once frames come out in increasing order, no later frame reads them.
  void release_through(int frame);
  // Whether the held buffers of `frame` are still read once every frame
  // before `next_out` is out (next_out past the shot's last frame: all are
  // out): by a frame not out yet (itself, or as the successor of its dt
  // layer), or by a window containing such a frame that is not solved yet.
  // Solved windows keep their solutions, so a streaming run holds about W
  // frames of buffers instead of W + H.
  bool buffers_needed(int frame, int next_out) const;

  int windows_solved() const { return windows_solved_; }
  int cached_windows() const { return int(solved_.size()); }

 private:
  Status solve(size_t window_index, const FrameLayers& layers, ReconStats* stats);

  TgptSettings settings_;
  std::vector<int> frames_;
  WindowSolver solve_;
  std::vector<WindowRange> windows_;
  std::map<size_t, std::vector<Image>> solved_;  // by window index
  int windows_solved_ = 0;
};

}  // namespace gdvr
