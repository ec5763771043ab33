// "What changes between frame t and t+1" (issue 4, "leave out what the scene
// does not need"): compares the two animated scene descriptions. If nothing a
// path can see moves, the temporal gradients of the pair are exactly zero
// (docs/tgpt.md, "Leaving out what the scene does not need"), so no temporal
// offsets, motion vectors or temporal buffers are needed for it.
#pragma once

#include <string>
#include <vector>

#include "core/scene/scene.h"

namespace gdvr {

struct FramePairChanges {
  bool camera = false;                // placement or projection
  std::vector<std::string> shapes;    // ids (or "#index") of shapes whose to_world changed
  std::vector<std::string> emitters;  // ids (or "#index") of emitters that moved or changed power
  // Materials cannot be animated in gdvr (tracks drive transforms only), but
  // they are compared all the same so that a future material track is caught.
  std::vector<std::string> materials;

  bool any() const { return camera || !shapes.empty() || !emitters.empty() || !materials.empty(); }
  // "camera, shapes smallbox" or "nothing".
  std::string describe() const;
};

// Both scenes must come from one loaded scene (same shape/emitter/BSDF lists),
// each after apply_animation at its frame's time.
FramePairChanges detect_changes(const Scene& at_t, const Scene& at_next);

}  // namespace gdvr
