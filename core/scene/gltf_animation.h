// glTF 2.0 node graph with TRS animation, evaluated exactly as the glTF 2.0
// specification defines it (section 3.11 and Appendix C "Interpolation"):
// every channel samples its own key times (STEP, LINEAR with quaternion slerp,
// CUBICSPLINE Hermite with tangents scaled by the key interval), a node's local
// matrix is T * R * S, and a node's world matrix is parent world * local at the
// same time. Independent of the glTF parser so it can be tested on its own.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "core/math/transform.h"
#include "core/scene/animation.h"

namespace gdvr {

enum class GltfPath { kTranslation, kRotation, kScale };
enum class GltfInterpolation { kStep, kLinear, kCubicSpline };

struct GltfSampler {
  GltfInterpolation interpolation = GltfInterpolation::kLinear;
  std::vector<double> times;   // strictly increasing, finite
  // components() values per key; CUBICSPLINE stores (in-tangent, value,
  // out-tangent) per key, so three times as many.
  std::vector<double> values;
  int components = 3;          // 3 for translation/scale, 4 for rotation (x, y, z, w)
};

struct GltfChannel {
  int node = -1;
  GltfPath path = GltfPath::kTranslation;
  GltfSampler sampler;
};

struct GltfNode {
  int parent = -1;
  bool has_matrix = false;     // static nodes may give a matrix instead of TRS
  Matrix4 matrix = Matrix4::identity();
  std::array<double, 3> translation{0, 0, 0};
  std::array<double, 4> rotation{0, 0, 0, 1};  // x, y, z, w
  std::array<double, 3> scale{1, 1, 1};
};

// Evaluates one sampler at `time` into out[0 .. components): clamped to the
// first/last key outside the key range; rotations come out normalised.
void evaluate_gltf_sampler(const GltfSampler& sampler, double time, double* out);

// T * R * S from glTF's translation, rotation (x, y, z, w) and scale.
Matrix4 gltf_trs_matrix(const std::array<double, 3>& t, const std::array<double, 4>& r, const std::array<double, 3>& s);

class GltfNodeGraph {
 public:
  std::vector<GltfNode> nodes;
  std::vector<GltfChannel> channels;

  // Local and world matrices at `time` (seconds from the animation's start).
  Matrix4 local_matrix(int node, double time) const;
  Matrix4 world_matrix(int node, double time) const;
  // True when a channel targets the node or one of its ancestors.
  bool is_animated(int node) const;
  // Sorted distinct key times of every channel on the node and its ancestors.
  std::vector<double> key_times(int node) const;
};

// The rotation and translation of an affine matrix, scale and shear removed
// (Gram-Schmidt on the columns). Cameras and lights ignore their node's scale:
// glTF says so for cameras, and a scaled spot would distort its cone.
Matrix4 gltf_remove_scale(const Matrix4& m);

// A track curve following one node of a shared graph: world(node, t) * offset
// (the offset converts glTF's camera and light frames to gdvr's), with the
// world's scale removed first when `rigid`.
class GltfNodeCurve : public TransformCurve {
 public:
  GltfNodeCurve(std::shared_ptr<const GltfNodeGraph> graph, int node, const Matrix4& offset, bool rigid)
      : graph_(std::move(graph)), node_(node), offset_(offset), rigid_(rigid) {}
  Transform evaluate(double time) const override;

 private:
  std::shared_ptr<const GltfNodeGraph> graph_;
  int node_;
  Matrix4 offset_;
  bool rigid_;
};

// Transform from a matrix, nudging a singular one (a scale keyed to zero to
// hide an object) to a tiny invertible scale so the renderer never sees NaN.
Transform gltf_to_transform(const Matrix4& m);

}  // namespace gdvr
