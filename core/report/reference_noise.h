// What the reference's own noise adds to each error figure of the report
// (docs/report.md, "The reference's own noise").
//
// A figure measures I against a reference R = truth + n, n zero-mean noise
// independent of I, so in expectation
//   E(I − R)² = (I − truth)² + Var(R):
// every squared error is inflated by the reference's variance. A rendered
// reference carries the per-pixel variance of its mean (PT's `variance`
// layer), which turns into the floor each figure cannot go below:
//   global     ΣVar(R) / ΣR²
//   per pixel  mean(Var(R) / (R² + 0.01))
//   flicker    mean over consecutive frames of mean(Var(R_t) + Var(R_t+1))
//              (the frames' noise is independent: each frame samples its own stream).
// A comparison between two methods is only meaningful where the floor is
// well below both figures; the report says where it is not.
#pragma once

#include <vector>

#include "core/image/image.h"
#include "core/report/report_results.h"
#include "core/util/status.h"

namespace gdvr {

// `references[i]` and `variances[i]` belong to the same frame, frames in shot
// order. Each variance has the reference's size and >= 3 channels (the first
// three are used). Non-finite variances count as 0. flicker needs >= 2 frames
// (kNoValue otherwise).
Expected<ReferenceNoiseFloor> reference_noise_floor(const std::vector<const Image*>& references,
                                                    const std::vector<const Image*>& variances);

}  // namespace gdvr
