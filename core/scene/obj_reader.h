// Wavefront OBJ meshes: v, vt, vn and f (polygons fan-triangulated, negative
// indices relative to the end). Materials, groups and smoothing groups are
// ignored: Mitsuba assigns the BSDF per <shape>, not per OBJ material.
#pragma once

#include <istream>
#include <string>

#include "core/scene/scene.h"
#include "core/util/status.h"

namespace gdvr {

struct ObjOptions {
  // Mitsuba's `flip_tex_coords` (default true): most OBJ exporters put v = 0
  // at the top of the image, Mitsuba's bitmaps at the bottom.
  bool flip_tex_coords = true;
};

Expected<TriangleMesh> read_obj(const std::string& path, const ObjOptions& options = {});
// `origin` names the source in error messages ("file.obj:12: ...").
Expected<TriangleMesh> parse_obj(std::istream& in, const std::string& origin, const ObjOptions& options = {});

}  // namespace gdvr
