// Streaming bookkeeping of a job's two stages (issue 4, "Streaming"): which
// frames to render, when a frame can be finalized (all buffers of its window
// are in), and which buffers can be dropped. Finalized frames come out in
// order as soon as their window is complete, and the buffers held are bounded
// by the window, not by the shot length (tested).
#pragma once

#include <cstddef>
#include <functional>
#include <set>
#include <vector>

namespace gdvr {

class StreamSchedule {
 public:
  // `todo`: the frames to finalize, in output order; `needs[i]`: the frames
  // whose buffers finalizing todo[i] reads (frames_needed_to_finalize), sorted.
  StreamSchedule(std::vector<int> todo, std::vector<std::vector<int>> needs);

  // Every frame some frame of `todo` needs, ascending: the render order.
  const std::vector<int>& render_order() const { return render_order_; }

  // Records that `frame`'s buffers are in.
  void rendered(int frame);
  // The next frame to finalize if all its needed frames have been rendered,
  // else -1 (also when done).
  int ready() const;
  // Records that ready() was finalized.
  void finalized();
  // Frames that were rendered and no frame still to finalize needs: drop them.
  std::vector<int> releasable();
  // Same, with a finer rule from the caller: a held frame is kept while
  // `still_needed(frame)` is true (tgpt: only windows not solved yet and the
  // next frames' own dt pairs; see temporal_window.h). The caller's rule must
  // keep whatever a frame still to finalize reads.
  std::vector<int> releasable(const std::function<bool(int frame)>& still_needed);
  int next_index() const { return int(next_); }  // index into `todo` of the next frame out
  bool done() const { return next_ >= todo_.size(); }

  int buffered() const { return int(held_.size()); }
  int max_buffered() const { return max_buffered_; }

 private:
  std::vector<int> todo_;
  std::vector<std::vector<int>> needs_;
  std::vector<int> render_order_;
  std::set<int> held_, seen_;
  size_t next_ = 0;
  int max_buffered_ = 0;
};

}  // namespace gdvr
