#include "core/temporal/temporal_window.h"

#include <algorithm>
#include <memory>
#include <set>

#include "core/recon/reconstruct.h"
#include "core/recon/sliding_window.h"
#include "core/temporal/temporal_buffers.h"

namespace gdvr {

std::vector<WindowRange> shot_windows(int n, int window, int hop) {
  // Mirrors SlidingWindowReconstructor::push / end_shot: a window is solved
  // when W frames from its start are in, the next starts H later, and at the
  // shot's end whatever is left after the last full window is one clamped window.
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

TemporalWindowCache::TemporalWindowCache(TgptSettings settings, int frame_count)
    : settings_(std::move(settings)), frame_count_(frame_count),
      windows_(shot_windows(frame_count, settings_.window, settings_.effective_hop())) {}

Status TemporalWindowCache::solve(const WindowRange& w, const ShotLayers& layers, ReconStats* stats) {
  GradientWindow window;
  for (int k = w.start; k < w.end; ++k) {
    const LayeredImage* cur = layers(k);
    if (!cur) return failed_precondition("tgpt: window [" + std::to_string(w.start) + ", " + std::to_string(w.end) +
                                         "): no buffers for shot position " + std::to_string(k));
    // Temporal terms only towards a frame inside the window: the window's
    // last frame has none (constraints leaving a window are dropped, §5).
    Expected<GradientFrame> gf = invalid_argument("unset");
    if (k + 1 < w.end) {
      const LayeredImage* next = layers(k + 1);
      if (!next) return failed_precondition("tgpt: no buffers for shot position " + std::to_string(k + 1));
      auto tg = temporal_gradients(*cur, *next, settings_);
      if (!tg.ok()) return tg.status();
      gf = tgpt_gradient_frame(*cur, &tg.value());
    } else {
      gf = tgpt_gradient_frame(*cur, nullptr);
    }
    if (!gf.ok()) return gf.status();
    window.frames.push_back(std::make_shared<const GradientFrame>(std::move(gf.value())));
  }
  auto result = ::gdvr::reconstruct(window, settings_.recon);
  if (!result.ok()) return result.status();
  if (stats) {
    stats->cg_iterations += result->stats.cg_iterations;
    stats->seconds += result->stats.seconds;
    for (int t = 0; t < kTermCount; ++t) {
      stats->non_finite_constraints[t] += result->stats.non_finite_constraints[t];
      stats->masked_constraints[t] += result->stats.masked_constraints[t];
    }
    stats->non_finite_outputs += result->stats.non_finite_outputs;
  }
  const int index = int(&w - windows_.data());
  solved_[index] = std::move(result->frames);
  ++windows_solved_;
  return Status::Ok();
}

Expected<Image> TemporalWindowCache::reconstruct(int index, const ShotLayers& layers, ReconStats* stats) {
  if (index < 0 || index >= frame_count_) return invalid_argument("tgpt: shot position out of range");
  Image sum;
  double weight = 0;
  // Same arithmetic, in the same order, as SlidingWindowReconstructor.
  for (size_t i = 0; i < windows_.size(); ++i) {
    const WindowRange& w = windows_[i];
    if (index < w.start || index >= w.end) continue;
    if (!solved_.count(int(i))) GDVR_RETURN_IF_ERROR(solve(w, layers, stats));
    const Image& img = solved_[int(i)][size_t(index - w.start)];
    const double hw = SlidingWindowReconstructor::hann_weight(index, w.start, settings_.window);
    if (sum.empty()) sum = Image(img.width(), img.height(), img.channels());
    for (size_t k = 0; k < sum.data().size(); ++k) sum.data()[k] += float(hw) * img.data()[k];
    weight += hw;
  }
  const float inv = weight > 0 ? float(1.0 / weight) : 0.0f;
  for (float& v : sum.data()) v *= inv;
  return sum;
}

bool TemporalWindowCache::buffers_needed(int position, int first_unfinalized) const {
  if (position >= first_unfinalized) return true;
  for (size_t i = 0; i < windows_.size(); ++i) {
    const WindowRange& w = windows_[i];
    if (w.end > first_unfinalized && w.start <= position && position < w.end && !solved_.count(int(i))) return true;
  }
  return false;
}

void TemporalWindowCache::release_before(int index) {
  for (auto it = solved_.begin(); it != solved_.end();)
    it = windows_[size_t(it->first)].end <= index ? solved_.erase(it) : std::next(it);
}

}  // namespace gdvr
