// Streaming driver for long shots (docs/reconstruction.md, "Sliding windows"): frames arrive
// in order, windows of W frames advance by a hop of H frames (default W/2, the
// public T-GPT code's 50 % overlap), and every frame's output is the blend of
// the solutions of all windows that contain it with Hann weights
// ½(1 + cos(2π(f − c)/W)), c the window's centre, normalised by their sum.
// With H = W/2 every frame lies in two windows whose weights sum to one, so
// each window solve pays for H output frames and the windows' seams (where a
// solve lacks the constraints beyond its border) get a weight near zero.
//
// A frame is final once the first window starting after it is about to be
// solved; it is then emitted, in order, exactly once. At a shot's end the
// last window is clamped to the shot (it may be shorter than W); a shot
// shorter than W is solved as one window. Memory: at most W input frames and
// W − H partially blended outputs are held.
#pragma once

#include <deque>
#include <functional>
#include <memory>
#include <vector>

#include "core/recon/gradient_window.h"
#include "core/recon/recon_settings.h"

namespace gdvr {

struct SlidingWindowOptions {
  int window = 20;  // W, frames per solve
  int hop = 0;      // H, frames between window starts; 0 = max(1, W/2)
  int effective_hop() const { return hop > 0 ? hop : (window / 2 > 0 ? window / 2 : 1); }
  Status validate() const;
};

struct ReconFrame {
  int index = 0;  // frame number within the shot
  Image image;
};

// Solves one window, returning one image per frame of the window.
using WindowSolver = std::function<Expected<std::vector<Image>>(const GradientWindow&)>;

class SlidingWindowReconstructor {
 public:
  SlidingWindowReconstructor(SlidingWindowOptions options, WindowSolver solve);
  // Solves each window with reconstruct(window, settings).
  static Expected<SlidingWindowReconstructor> create(SlidingWindowOptions options, ReconSettings settings);

  // Adds the next frame of the shot; appends the frames that became final.
  Status push(std::shared_ptr<const GradientFrame> frame, std::vector<ReconFrame>* out);
  // Ends the shot: solves what is left, appends the remaining frames, and
  // resets for the next shot (frame numbers restart at 0).
  Status end_shot(std::vector<ReconFrame>* out);

  int buffered_frames() const { return int(frames_.size()); }
  int max_buffered_frames() const { return max_buffered_; }
  int windows_solved() const { return windows_solved_; }

  // Hann weight of frame f in the window starting at `start` with nominal
  // size W (always > 0 inside the window).
  static double hann_weight(int f, int start, int window);

 private:
  struct Accum {
    Image sum;
    double weight = 0;
  };
  Status solve_window(int start, int end);
  void emit_until(int end, std::vector<ReconFrame>* out);
  void reset();

  SlidingWindowOptions options_;
  WindowSolver solve_;
  std::deque<std::shared_ptr<const GradientFrame>> frames_;  // shot frames [first_, pushed_)
  int first_ = 0;
  int pushed_ = 0;
  int next_start_ = 0;  // start of the next window to solve
  int solved_end_ = 0;  // end of the last solved window
  std::deque<Accum> accum_;  // blends for frames [emitted_, solved_end_)
  int emitted_ = 0;
  int max_buffered_ = 0;
  int windows_solved_ = 0;
};

}  // namespace gdvr
