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
#include <memory>
#include <set>
#include <vector>

#include "core/image/image.h"
#include "core/image/pixel_rect.h"
#include "core/recon/gradient_window.h"
#include "core/recon/recon_result.h"
#include "core/recon/tiled_reconstruct.h"
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

// Solves one window (or one tile of it: docs/reconstruction.md, "Tiled
// solve"): one image per frame of the window, and the solve's numbers, whose
// dropped-constraint counts cover the pixels of `counted` only (a tile's core).
using WindowSolver = std::function<Expected<ReconResult>(const GradientWindow&, const PixelRect& counted)>;

// A shot's stage-1 buffers as the window solve reads them, a region at a time:
// a tiled solve (frames larger than recon.tile_size) reads each tile's part of
// the window's frames only, so the frames may live on disk
// (spilling_frame_store.h) and stage 2 holds one tile of the window at a time.
struct FrameRegionReader {
  int width = 0, height = 0;  // of the shot's frames
  // `frame`'s layers cropped to `rect`: null when its buffers are not
  // available, an error when reading them fails.
  std::function<Expected<std::shared_ptr<const LayeredImage>>(int frame, const PixelRect& rect)> read;
};
// Region reads of frames held whole in memory (`layers` gives null for a
// frame it lacks): the whole frame is borrowed, a region is a copy.
FrameRegionReader in_memory_region_reader(int width, int height,
                                          std::function<const LayeredImage*(int frame)> layers);

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
  // the windows not solved yet, by tiles when the frames are larger than
  // recon.tile_size.
  Expected<Image> reconstruct(int frame, const FrameLayers& layers, ReconStats* stats);
  // Same, reading the frames' buffers a region at a time.
  Expected<Image> reconstruct(int frame, const FrameRegionReader& reader, ReconStats* stats);
  // Frees the solutions of windows whose last frame is `frame` or earlier, and
  // the solved images of frames up to `frame` in the windows kept: once frames
  // come out in increasing order, no later frame reads them (a frame asked
  // for again is solved again).
  void release_through(int frame);
  // Whether the held buffers of `frame` are still read once every frame
  // before `next_out` is out (next_out past the shot's last frame: all are
  // out): by a frame not out yet (itself, or as the successor of its dt
  // layer), or by a window containing such a frame that is not solved yet.
  // Solved windows keep their solutions, so a streaming run holds about W
  // frames of buffers instead of W + H.
  bool buffers_needed(int frame, int next_out) const;

  // Solve only these tiles of the tile grid (tiled_reconstruct.h; all when
  // empty): a farm's tiled finalize, where each task solves some tiles and a
  // last step pastes them together. Pixels outside their cores come out 0.
  // Changing the subset forgets what was solved.
  void solve_only_tiles(std::vector<int> tiles);
  // The tile grid the windows are solved with, for frames of width × height.
  Expected<TileGrid> tile_grid(int width, int height) const { return tile_grid_for(settings_.recon, width, height); }

  int windows_solved() const { return windows_solved_; }
  // Windows solved whose frames are not all out yet.
  int cached_windows() const { return int(solved_.size()); }

 private:
  // A frame's blend so far: Σ weight · solution over the windows in
  // `windows`, always added in increasing window order (so a frame's image
  // does not depend on the order frames are asked for).
  struct Blend {
    Image sum;
    double weight = 0;
    std::set<size_t> windows;
  };
  // Solves window `window_index` (by tiles if the frames are large) and adds
  // its solution to the blends of its frames not out yet and of
  // `requested` (a shot position).
  Status solve(size_t window_index, int requested, const FrameRegionReader& reader, ReconStats* stats);
  // Adds `weight` × `solved` (a region `core` of a tile of the window, placed
  // at `at` in the frame) to the blend of shot position `index`.
  void add_to_blend(size_t window_index, int index, const Image& solved, const PixelRect& core, int at_x, int at_y,
                    int width, int height);
  // The window's frames cropped to `rect`, as the reconstruction sees them.
  Expected<GradientWindow> gradient_window(const WindowRange& w, const FrameRegionReader& reader,
                                           const PixelRect& rect) const;
  // FAILED_PRECONDITION where some of the window's frames carry a denoised
  // data term and others do not.
  Status check_one_data_term(const GradientWindow& window, const WindowRange& w) const;

  TgptSettings settings_;
  std::vector<int> frames_;
  WindowSolver solve_;
  std::vector<WindowRange> windows_;
  std::map<int, Blend> blends_;  // by shot position, frames not out yet
  std::set<size_t> solved_;      // windows solved whose frames are not all out
  int released_end_ = 0;         // shot positions before it are out
  std::vector<int> tile_subset_;  // empty: every tile
  int windows_solved_ = 0;
};

}  // namespace gdvr
