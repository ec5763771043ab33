#include "core/temporal/stream_schedule.h"

#include <algorithm>

namespace gdvr {

StreamSchedule::StreamSchedule(std::vector<int> todo, std::vector<std::vector<int>> needs)
    : todo_(std::move(todo)), needs_(std::move(needs)) {
  std::set<int> all;
  for (const auto& n : needs_) all.insert(n.begin(), n.end());
  render_order_.assign(all.begin(), all.end());
}

void StreamSchedule::rendered(int frame) {
  held_.insert(frame);
  seen_.insert(frame);
  max_buffered_ = std::max(max_buffered_, int(held_.size()));
}

int StreamSchedule::ready() const {
  if (done()) return -1;
  for (int f : needs_[next_])
    if (!seen_.count(f)) return -1;
  return todo_[next_];
}

void StreamSchedule::finalized() { ++next_; }

std::vector<int> StreamSchedule::releasable() {
  std::set<int> keep;
  for (size_t i = next_; i < todo_.size(); ++i) {
    // needs are windows moving forward: once a frame's needs start after the
    // last held buffer, no later frame needs a held one.
    if (!needs_[i].empty() && !held_.empty() && needs_[i].front() > *held_.rbegin()) break;
    keep.insert(needs_[i].begin(), needs_[i].end());
  }
  std::vector<int> out;
  for (auto it = held_.begin(); it != held_.end();) {
    if (keep.count(*it)) {
      ++it;
    } else {
      out.push_back(*it);
      it = held_.erase(it);
    }
  }
  return out;
}

std::vector<int> StreamSchedule::releasable(const std::function<bool(int)>& still_needed) {
  std::vector<int> out;
  for (auto it = held_.begin(); it != held_.end();) {
    if (still_needed(*it)) {
      ++it;
    } else {
      out.push_back(*it);
      it = held_.erase(it);
    }
  }
  return out;
}

}  // namespace gdvr
