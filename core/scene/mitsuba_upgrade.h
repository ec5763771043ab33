// Mitsuba 0.x scene files (<scene version="0.5.0">, any version below 2.0.0)
// in Mitsuba 3's terms. Mitsuba 3 upgrades such files in memory when it loads
// them; gdvr applies the same rules to the element tree of mitsuba_xml.h, per
// file (an included file is upgraded by its own version), before the loader
// (mitsuba_loader.cpp) sees it:
//   - every parameter name goes from camelCase to snake_case (maxDepth ->
//     max_depth, intIOR -> int_ior, toWorld -> to_world);
//   - <lookAt> becomes <lookat>;
//   - ids starting with '_' (reserved in Mitsuba 3) become "ID" + id + "__UPGR";
//   - a diffuse BSDF's diffuse_reflectance becomes reflectance;
//   - the floats uoffset/voffset/uscale/vscale become a to_uv transform
//     (translate, then scale).
#pragma once

#include <string>
#include <vector>

#include "core/scene/mitsuba_xml.h"
#include "core/util/status.h"

namespace gdvr {

struct SceneVersion {
  unsigned major = 0, minor = 0, patch = 0;

  // Files older than Mitsuba 2 use the 0.x names and need the upgrade.
  bool is_legacy() const { return major < 2; }
};

// Parses a <scene> version as Mitsuba does: three numbers separated by '.'
// (or spaces), e.g. "0.5.0". False when the text is not of that form.
bool parse_scene_version(const std::string& text, SceneVersion* out);

// "maxDepth" -> "max_depth", "intIOR" -> "int_ior", "fovAxis" -> "fov_axis":
// each lowercase letter followed by uppercase ones gets a '_' and the run of
// uppercase letters is lowercased. Names without such a pair are unchanged.
std::string camel_to_snake_case(const std::string& name);

// Upgrades, in place, every element of the tree under `root` (root included)
// whose source file is legacy (XmlSource::legacy); elements of other files are
// left alone. Renamed ids are reported in `warnings`. Fails (naming file and
// line) on a uoffset/voffset/uscale/vscale that is not one number.
Status upgrade_legacy_elements(XmlElement* root, std::vector<std::string>* warnings);

}  // namespace gdvr
