#include "core/temporal/temporal_window.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <set>

#include "core/recon/reconstruct.h"
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

TemporalWindowCache::TemporalWindowCache(TgptSettings settings, std::vector<int> frames, WindowSolver solve)
    : settings_(std::move(settings)), frames_(std::move(frames)), solve_(std::move(solve)),
      windows_(shot_windows(int(frames_.size()), settings_.window, settings_.effective_hop())) {
  if (!solve_)
    solve_ = [recon = settings_.recon](const GradientWindow& w) { return ::gdvr::reconstruct(w, recon); };
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

Status TemporalWindowCache::solve(size_t window_index, const FrameLayers& layers, ReconStats* stats) {
  const WindowRange& w = windows_[window_index];
  auto missing = [&](int k) {
    return failed_precondition("tgpt: window of frames " + std::to_string(frames_[size_t(w.start)]) + "-" +
                               std::to_string(frames_[size_t(w.end - 1)]) + ": no buffers for frame " +
                               std::to_string(frames_[size_t(k)]));
  };
  GradientWindow window;
  for (int k = w.start; k < w.end; ++k) {
    const LayeredImage* cur = layers(frames_[size_t(k)]);
    if (!cur) return missing(k);
    // Temporal terms only towards a frame inside the window: the window's
    // last frame has none (constraints leaving a window are dropped, §5).
    Expected<GradientFrame> gf = invalid_argument("unset");
    if (k + 1 < w.end) {
      const LayeredImage* next = layers(frames_[size_t(k) + 1]);
      if (!next) return missing(k + 1);
      auto tg = temporal_gradients(*cur, *next, settings_);
      if (!tg.ok()) return tg.status();
      gf = tgpt_gradient_frame(*cur, &tg.value());
    } else {
      gf = tgpt_gradient_frame(*cur, nullptr);
    }
    if (!gf.ok()) return gf.status();
    window.frames.push_back(std::make_shared<const GradientFrame>(std::move(gf.value())));
  }
  Expected<ReconResult> result = solve_(window);
  if (!result.ok()) return result.status();
  if (int(result->frames.size()) != w.end - w.start)
    return internal_error("tgpt: the window solver returned " + std::to_string(result->frames.size()) +
                          " frames for a window of " + std::to_string(w.end - w.start));
  if (stats) {
    stats->cg_iterations += result->stats.cg_iterations;
    stats->seconds += result->stats.seconds;
    for (int t = 0; t < kTermCount; ++t) {
      stats->non_finite_constraints[t] += result->stats.non_finite_constraints[t];
      stats->masked_constraints[t] += result->stats.masked_constraints[t];
    }
    stats->non_finite_outputs += result->stats.non_finite_outputs;
  }
  solved_[window_index] = std::move(result->frames);
  ++windows_solved_;
  return Status::Ok();
}

Expected<Image> TemporalWindowCache::reconstruct(int frame, const FrameLayers& layers, ReconStats* stats) {
  const int index = position(frame);
  if (index < 0) return invalid_argument("tgpt: frame " + std::to_string(frame) + " is not in the shot");
  Image sum;
  double weight = 0;
  for (size_t i = 0; i < windows_.size(); ++i) {
    const WindowRange& w = windows_[i];
    if (index < w.start || index >= w.end) continue;
    if (!solved_.count(i)) GDVR_RETURN_IF_ERROR(solve(i, layers, stats));
    const Image& img = solved_[i][size_t(index - w.start)];
    const double hw = window_blend_weight(index, w.start, settings_.window);
    if (sum.empty()) sum = Image(img.width(), img.height(), img.channels());
    for (size_t k = 0; k < sum.data().size(); ++k) sum.data()[k] += float(hw) * img.data()[k];
    weight += hw;
  }
  const float inv = weight > 0 ? float(1.0 / weight) : 0.0f;
  for (float& v : sum.data()) v *= inv;
  return sum;
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
    it = windows_[it->first].end <= end ? solved_.erase(it) : std::next(it);
}

}  // namespace gdvr
