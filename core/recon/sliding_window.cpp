#include "core/recon/sliding_window.h"

#include <cmath>

#include "core/recon/reconstruct.h"

namespace gdvr {

Status SlidingWindowOptions::validate() const {
  if (window < 1) return invalid_argument("sliding window: window must be >= 1, got " + std::to_string(window));
  if (hop < 0 || hop > window)
    return invalid_argument("sliding window: hop must be in [0, window] (0 = window/2), got " + std::to_string(hop));
  return Status::Ok();
}

SlidingWindowReconstructor::SlidingWindowReconstructor(SlidingWindowOptions options, WindowSolver solve)
    : options_(options), solve_(std::move(solve)) {}

Expected<SlidingWindowReconstructor> SlidingWindowReconstructor::create(SlidingWindowOptions options,
                                                                        ReconSettings settings) {
  GDVR_RETURN_IF_ERROR(options.validate());
  GDVR_RETURN_IF_ERROR(settings.validate());
  return SlidingWindowReconstructor(options, [settings](const GradientWindow& w) -> Expected<std::vector<Image>> {
    Expected<ReconResult> r = reconstruct(w, settings);
    if (!r.ok()) return r.status();
    return std::move(r.value().frames);
  });
}

double SlidingWindowReconstructor::hann_weight(int f, int start, int window) {
  const double centre = start + 0.5 * (window - 1);
  return 0.5 * (1.0 + std::cos(2.0 * M_PI * (f - centre) / window));
}

Status SlidingWindowReconstructor::push(std::shared_ptr<const GradientFrame> frame, std::vector<ReconFrame>* out) {
  GDVR_RETURN_IF_ERROR(options_.validate());
  if (!frame) return invalid_argument("sliding window: null frame");
  frames_.push_back(std::move(frame));
  ++pushed_;
  max_buffered_ = std::max(max_buffered_, int(frames_.size()));
  if (pushed_ - next_start_ < options_.window) return Status::Ok();

  GDVR_RETURN_IF_ERROR(solve_window(next_start_, pushed_));
  next_start_ += options_.effective_hop();
  // Frames before the next window's start belong to no later window.
  emit_until(next_start_, out);
  while (first_ < next_start_) {
    frames_.pop_front();
    ++first_;
  }
  return Status::Ok();
}

Status SlidingWindowReconstructor::end_shot(std::vector<ReconFrame>* out) {
  if (pushed_ > solved_end_) GDVR_RETURN_IF_ERROR(solve_window(next_start_, pushed_));
  emit_until(pushed_, out);
  reset();
  return Status::Ok();
}

Status SlidingWindowReconstructor::solve_window(int start, int end) {
  GradientWindow window;
  for (int f = start; f < end; ++f) window.frames.push_back(frames_[f - first_]);
  Expected<std::vector<Image>> solved = solve_(window);
  if (!solved.ok())
    return solved.status().with_context("sliding window [" + std::to_string(start) + ", " + std::to_string(end) +
                                        "): ");
  if (int(solved.value().size()) != end - start)
    return internal_error("sliding window: solver returned " + std::to_string(solved.value().size()) +
                          " frames for a window of " + std::to_string(end - start));
  while (emitted_ + int(accum_.size()) < end) accum_.emplace_back();
  for (int f = start; f < end; ++f) {
    const Image& img = solved.value()[f - start];
    Accum& a = accum_[f - emitted_];
    const double w = hann_weight(f, start, options_.window);
    if (a.sum.empty()) a.sum = Image(img.width(), img.height(), img.channels());
    std::vector<float>& sum = a.sum.data();
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += float(w) * img.data()[i];
    a.weight += w;
  }
  solved_end_ = end;
  ++windows_solved_;
  return Status::Ok();
}

void SlidingWindowReconstructor::emit_until(int end, std::vector<ReconFrame>* out) {
  while (emitted_ < end && !accum_.empty()) {
    Accum& a = accum_.front();
    const float inv = a.weight > 0 ? float(1.0 / a.weight) : 0.0f;
    for (float& v : a.sum.data()) v *= inv;
    out->push_back({emitted_, std::move(a.sum)});
    accum_.pop_front();
    ++emitted_;
  }
}

void SlidingWindowReconstructor::reset() {
  frames_.clear();
  accum_.clear();
  first_ = pushed_ = next_start_ = solved_end_ = emitted_ = 0;
}

}  // namespace gdvr
