// glTF 2.0 (.gltf/.glb) scenes with their node animation.
//
// What maps onto what (details and approximations at each builder in
// gltf_loader.cpp; every approximation also lands in Scene::warnings):
// - Mesh primitives (triangles) -> one Shape each, to_world = the node's world
//   transform. Shape ids are node names (or "node<index>"), made unique; all
//   primitives of a node share its id, so one job track moves the whole node.
// - The default scene's node hierarchy with TRS animation (STEP, LINEAR,
//   CUBICSPLINE) -> one Track per animated shape, light and camera, whose
//   TransformCurve evaluates the node graph exactly (gltf_animation.h). All
//   animations of the file play together from t = 0.
// - The first perspective camera met in the scene's node order -> Scene::camera
//   (id = its node's id; a job's "sensor" track still applies on top).
//   Without a camera a default one frames the bounding box (warning).
// - KHR_lights_punctual -> point, spot, directional emitters (id = node id).
// - Metallic-roughness materials -> roughconductor / roughplastic (GGX),
//   emissive (with KHR_materials_emissive_strength) -> area emitters.
// - Skinning, morph targets, orthographic cameras, non-triangle primitives and
//   unsupported required extensions -> kUnimplemented errors naming the item.
// The result is plain Scene data: a caller may append emitters (lights, an
// environment) or tracks before rendering, as for a Mitsuba scene.
#pragma once

#include <string>

#include "core/scene/scene_loader.h"

namespace gdvr {

Expected<LoadedScene> load_gltf_scene(const std::string& path, const LoadOptions& options);

}  // namespace gdvr
