// The stage-1 frames a T-GPT stage 2 holds while their windows are solved
// (docs/tgpt.md, "Memory"), kept in memory up to a byte limit and spilled to
// raw files beyond it (core/io/layer_spill_file.h). A tiled window solve
// reads each tile's part of a spilled frame, so stage 2's memory no longer
// grows with W frames of buffers.
#pragma once

#include <map>
#include <memory>
#include <string>

#include "core/io/layer_spill_file.h"
#include "core/temporal/temporal_window.h"

namespace gdvr {

class SpillingFrameStore {
 public:
  // `memory_limit_bytes`: the frames kept in memory (their pixels) stay
  // within it, the others go to files in `spill_dir` (which must exist;
  // LayerSpillFile::spill); < 0: no limit, nothing is spilled.
  SpillingFrameStore(std::string spill_dir, long long memory_limit_bytes);
  ~SpillingFrameStore();  // spill files have no name: closing them frees the disk
  SpillingFrameStore(const SpillingFrameStore&) = delete;
  SpillingFrameStore& operator=(const SpillingFrameStore&) = delete;

  // Every frame must have the size of the first.
  Status put(int frame, LayeredImage layers);
  void erase(int frame);
  bool has(int frame) const { return memory_.count(frame) || spilled_.count(frame); }
  // The whole frame: borrowed when in memory, read back when spilled; null if absent.
  Expected<std::shared_ptr<const LayeredImage>> whole(int frame) const;
  // Region reads for TemporalWindowCache::reconstruct (valid while the store lives).
  FrameRegionReader reader() const;

  long long bytes_in_memory() const { return bytes_in_memory_; }
  int spilled_frames() const { return int(spilled_.size()); }
  int most_spilled_frames() const { return most_spilled_; }

 private:
  std::string dir_;
  long long limit_;
  int width_ = 0, height_ = 0;
  std::map<int, LayeredImage> memory_;
  std::map<int, std::unique_ptr<LayerSpillFile>> spilled_;
  long long bytes_in_memory_ = 0;
  int most_spilled_ = 0;
};

}  // namespace gdvr
