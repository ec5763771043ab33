#include "core/temporal/temporal_window.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

#include "core/image/image_region.h"
#include "core/recon/reconstruct.h"
#include "core/recon/tiled_reconstruct.h"
#include "core/temporal/temporal_buffers.h"

namespace gdvr {

std::vector<WindowRange> shot_windows(int n, int window, int hop) {
  // As frames stream in: a window is solved when W frames from its start are
  // in, the next starts H later, and at the shot's end whatever is left after
  // the last full window is one clamped window.
  std::vector<WindowRange> out;
  if (n <= 0) return out;
  window = std::max(1, window);
  hop = hop > 0 ? hop : std::max(1, window / 2);
  int start = 0, solved_end = 0;
  while (start + window <= n) {
    out.push_back({start, start + window});
    solved_end = start + window;
    start += hop;
  }
  if (n > solved_end) out.push_back({start, n});
  return out;
}

std::vector<int> positions_needed(int n, int window, int hop, int index) {
  std::set<int> need;
  for (const WindowRange& w : shot_windows(n, window, hop))
    if (w.start <= index && index < w.end)
      for (int k = w.start; k < w.end; ++k) need.insert(k);
  need.insert(index);
  if (index + 1 < n) need.insert(index + 1);
  return {need.begin(), need.end()};
}

double window_blend_weight(int index, int start, int window) {
  const double centre = start + 0.5 * (window - 1);
  return 0.5 * (1.0 + std::cos(2.0 * M_PI * (index - centre) / window));
}

FrameRegionReader in_memory_region_reader(int width, int height,
                                          std::function<const LayeredImage*(int frame)> layers) {
  FrameRegionReader r;
  r.width = width;
  r.height = height;
  r.read = [width, height, layers = std::move(layers)](
               int f, const PixelRect& rect) -> Expected<std::shared_ptr<const LayeredImage>> {
    const LayeredImage* l = layers(f);
    if (!l) return std::shared_ptr<const LayeredImage>();
    if (rect == PixelRect::whole(width, height)) return std::shared_ptr<const LayeredImage>(l, [](const LayeredImage*) {});
    return std::shared_ptr<const LayeredImage>(std::make_shared<LayeredImage>(crop_layers(*l, rect)));
  };
  return r;
}

TemporalWindowCache::TemporalWindowCache(TgptSettings settings, std::vector<int> frames, WindowSolver solve)
    : settings_(std::move(settings)), frames_(std::move(frames)), solve_(std::move(solve)),
      windows_(shot_windows(int(frames_.size()), settings_.window, settings_.effective_hop())) {
  if (!solve_)
    solve_ = [recon = settings_.recon](const GradientWindow& w, const PixelRect& counted) {
      return ::gdvr::reconstruct(w, recon, counted);
    };
}

int TemporalWindowCache::position(int frame) const {
  auto it = std::lower_bound(frames_.begin(), frames_.end(), frame);
  return it != frames_.end() && *it == frame ? int(it - frames_.begin()) : -1;
}

std::vector<int> TemporalWindowCache::frames_needed(int frame) const {
  const int pos = position(frame);
  if (pos < 0) return {frame};
  std::vector<int> out;
  for (int p : positions_needed(int(frames_.size()), settings_.window, settings_.effective_hop(), pos))
    out.push_back(frames_[size_t(p)]);
  return out;
}

Expected<GradientWindow> TemporalWindowCache::gradient_window(const WindowRange& w, const FrameRegionReader& reader,
                                                              const PixelRect& rect) const {
  auto read = [&](int k) -> Expected<std::shared_ptr<const LayeredImage>> {
    auto layers = reader.read(frames_[size_t(k)], rect);
    if (layers.ok() && !layers.value())
      return failed_precondition("tgpt: window of frames " + std::to_string(frames_[size_t(w.start)]) + "-" +
                                 std::to_string(frames_[size_t(w.end - 1)]) + ": no buffers for frame " +
                                 std::to_string(frames_[size_t(k)]));
    return layers;
  };
  const GradientVariances variances = gradient_variances_for(settings_.recon.method);
  GradientWindow window;
  // Each frame's region is read once: frame k's is the `next` of frame k−1.
  auto cur = read(w.start);
  if (!cur.ok()) return cur.status();
  for (int k = w.start; k < w.end; ++k) {
    // Temporal terms only towards a frame inside the window: the window's
    // last frame has none (constraints leaving a window are dropped, §5).
    Expected<GradientFrame> gf = invalid_argument("unset");
    Expected<std::shared_ptr<const LayeredImage>> next = std::shared_ptr<const LayeredImage>();
    if (k + 1 < w.end) {
      next = read(k + 1);
      if (!next.ok()) return next.status();
      auto tg = temporal_gradients(**cur, **next, settings_);
      if (!tg.ok()) return tg.status();
      gf = tgpt_gradient_frame(**cur, &tg.value(), variances, settings_.data_term);
    } else {
      gf = tgpt_gradient_frame(**cur, nullptr, variances, settings_.data_term);
    }
    if (!gf.ok()) return gf.status().with_context("frame " + std::to_string(frames_[size_t(k)]) + ": ");
    window.frames.push_back(std::make_shared<const GradientFrame>(std::move(gf.value())));
    cur = std::move(next);
  }
  GDVR_RETURN_IF_ERROR(check_one_data_term(window, w));
  return window;
}

// A window's frames must share their data term. One process renders every
// frame with the same one, but a farm's render tasks under data_term "auto"
// resolve it on each worker: a worker without a denoiser renders the sampled
// term. A window of both would weigh its frames' primals by two different
// rules (core/temporal/denoised_data_term.h), so it is refused, naming a
// frame of each.
Status TemporalWindowCache::check_one_data_term(const GradientWindow& window, const WindowRange& w) const {
  int with = -1, without = -1;
  for (int k = w.start; k < w.end; ++k) {
    const bool denoised = !window.frames[size_t(k - w.start)]->data_weight.empty();
    (denoised ? with : without) = frames_[size_t(k)];
  }
  if (with < 0 || without < 0) return Status::Ok();
  return failed_precondition(
      "tgpt: window of frames " + std::to_string(frames_[size_t(w.start)]) + "-" +
      std::to_string(frames_[size_t(w.end - 1)]) + " mixes data terms: frame " + std::to_string(with) +
      "'s buffers carry the denoised data term and frame " + std::to_string(without) +
      "'s do not (render tasks on machines with and without a denoiser under reconstruction.data_term "
      "'auto'); render every frame with one data term: set 'denoised' or 'sampled', or render frame " +
      std::to_string(without) + " again where the denoiser is");
}

void TemporalWindowCache::add_to_blend(size_t window_index, int index, const Image& solved, const PixelRect& core,
                                       int at_x, int at_y, int width, int height) {
  Blend& b = blends_[index];
  if (b.sum.empty()) b.sum = Image(width, height, solved.channels());
  const float w = float(window_blend_weight(index, windows_[window_index].start, settings_.window));
  const int C = solved.channels();
  for (int y = core.y0; y < core.y1; ++y) {
    const float* from = solved.data().data() + (size_t(y) * solved.width() + core.x0) * C;
    float* to = b.sum.data().data() + (size_t(at_y + y - core.y0) * width + at_x) * C;
    for (int k = 0; k < core.width() * C; ++k) to[k] += w * from[k];
  }
}

Status TemporalWindowCache::solve(size_t window_index, int requested, const FrameRegionReader& reader,
                                  ReconStats* stats) {
  const WindowRange& w = windows_[window_index];
  // The frames this solve adds to: those not out yet (and the one asked for)
  // that lack this window and no later one (a blend that holds a later
  // window lacking this one is dropped: it is rebuilt in order if asked for).
  std::vector<int> targets;
  for (int k = w.start; k < w.end; ++k) {
    if (k < released_end_ && k != requested) continue;
    auto it = blends_.find(k);
    if (it != blends_.end() && it->second.windows.count(window_index)) continue;
    if (it != blends_.end() && !it->second.windows.empty() && *it->second.windows.rbegin() > window_index) {
      blends_.erase(it);
      if (k != requested) continue;
    }
    targets.push_back(k);
  }
  auto sink = [&](const ReconTile& tile, const ReconResult& solved, const PixelRect& core) {
    if (int(solved.frames.size()) != w.end - w.start)
      return internal_error("tgpt: the window solver returned " + std::to_string(solved.frames.size()) +
                            " frames for a window of " + std::to_string(w.end - w.start));
    for (int k : targets)
      add_to_blend(window_index, k, solved.frames[size_t(k - w.start)], core, tile.core.x0, tile.core.y0,
                   reader.width, reader.height);
    return Status::Ok();
  };
  // One tile when the frames are no larger than recon.tile_size: the whole
  // window, solved as before. Otherwise each tile reads its part of the
  // window's frames and forms their gradients, so stage 2 holds one tile of
  // the window at a time.
  auto grid = tile_grid_for(settings_.recon, reader.width, reader.height);
  if (!grid.ok()) return grid.status();
  auto solved = solve_tiles(
      grid.value(), w.end - w.start, [&](const PixelRect& padded) { return gradient_window(w, reader, padded); },
      solve_, sink, tile_subset_);
  if (!solved.ok()) {
    // Some tiles may have been added: those blends are incomplete.
    for (int k : targets) blends_.erase(k);
    return solved.status();
  }
  for (int k : targets) {
    Blend& b = blends_[k];
    b.weight += window_blend_weight(k, w.start, settings_.window);
    b.windows.insert(window_index);
  }
  if (stats) {
    stats->cg_iterations += solved->cg_iterations;
    stats->seconds += solved->seconds;
    for (int t = 0; t < kTermCount; ++t) {
      stats->non_finite_constraints[t] += solved->non_finite_constraints[t];
      stats->masked_constraints[t] += solved->masked_constraints[t];
    }
    stats->non_finite_outputs += solved->non_finite_outputs;
  }
  solved_.insert(window_index);
  ++windows_solved_;
  return Status::Ok();
}

Expected<Image> TemporalWindowCache::reconstruct(int frame, const FrameLayers& layers, ReconStats* stats) {
  int width = 0, height = 0;
  for (int f : frames_needed(frame))
    if (const LayeredImage* l = layers(f); l && !l->layers.empty()) {
      width = l->layers.front().image.width();
      height = l->layers.front().image.height();
      break;
    }
  return reconstruct(frame, in_memory_region_reader(width, height, layers), stats);
}

Expected<Image> TemporalWindowCache::reconstruct(int frame, const FrameRegionReader& reader, ReconStats* stats) {
  const int index = position(frame);
  if (index < 0) return invalid_argument("tgpt: frame " + std::to_string(frame) + " is not in the shot");
  std::vector<size_t> containing;
  for (size_t i = 0; i < windows_.size(); ++i)
    if (windows_[i].start <= index && index < windows_[i].end) containing.push_back(i);
  // A blend must be built in window order; one that is not (frames asked for
  // out of order) starts again.
  if (auto it = blends_.find(index);
      it != blends_.end() && !it->second.windows.empty() && *it->second.windows.begin() != containing.front())
    blends_.erase(it);
  for (size_t i : containing)
    if (!blends_.count(index) || !blends_[index].windows.count(i)) GDVR_RETURN_IF_ERROR(solve(i, index, reader, stats));
  Blend& b = blends_[index];
  Image out = std::move(b.sum);
  const float inv = b.weight > 0 ? float(1.0 / b.weight) : 0.0f;
  for (float& v : out.data()) v *= inv;
  // Its image is handed out; asked for again it is solved again.
  blends_.erase(index);
  return out;
}

void TemporalWindowCache::solve_only_tiles(std::vector<int> tiles) {
  if (tiles == tile_subset_) return;
  tile_subset_ = std::move(tiles);
  blends_.clear();
  solved_.clear();
}

bool TemporalWindowCache::buffers_needed(int frame, int next_out) const {
  const int pos = position(frame);
  const int first = int(std::lower_bound(frames_.begin(), frames_.end(), next_out) - frames_.begin());
  if (pos < 0 || pos >= first) return true;
  for (size_t i = 0; i < windows_.size(); ++i) {
    const WindowRange& w = windows_[i];
    if (w.end > first && w.start <= pos && pos < w.end && !solved_.count(i)) return true;
  }
  return false;
}

void TemporalWindowCache::release_through(int frame) {
  const int end = int(std::upper_bound(frames_.begin(), frames_.end(), frame) - frames_.begin());
  for (auto it = solved_.begin(); it != solved_.end();)
    it = windows_[*it].end <= end ? solved_.erase(it) : std::next(it);
  blends_.erase(blends_.begin(), blends_.lower_bound(end));
  released_end_ = std::max(released_end_, end);
}

}  // namespace gdvr
