// glTF 2.0 loader on Debian's header-only tinygltf. The implementation lives in
// this one translation unit; images are kept encoded by tinygltf and decoded
// here (stb, a private static copy) only when a material uses them.
#include "core/scene/gltf_loader.h"

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_ONLY_JPEG
#include <stb/stb_image.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "core/scene/gltf_animation.h"
#include "core/scene/mesh_repair.h"
#include "core/util/path_confinement.h"

namespace gdvr {

namespace {

namespace fs = std::filesystem;

constexpr double kPiD = 3.14159265358979323846;
// Below this GGX alpha (roughness ~0.03) the smooth BSDF variant is used: the
// rough ones become numerically fragile and visually identical.
constexpr float kSmoothAlpha = 1e-3f;

// ---- tinygltf callbacks ----

// Keeps the encoded bytes; decode_image() decodes on first use by a material.
bool keep_encoded_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
  image->image.assign(bytes, bytes + size);
  image->width = image->height = -1;
  image->as_is = true;
  return true;
}

struct FsContext {
  std::string asset_root;
};

// No '~' or environment expansion: a file in a scene names a file, nothing more.
std::string expand_nothing(const std::string& path, void*) { return path; }

bool file_exists(const std::string& path, void* user) {
  const auto* ctx = static_cast<const FsContext*>(user);
  if (!ctx->asset_root.empty() && !is_inside_root(path, ctx->asset_root)) return false;
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

bool read_whole_file(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  const auto* ctx = static_cast<const FsContext*>(user);
  if (!ctx->asset_root.empty() && !is_inside_root(path, ctx->asset_root)) {
    if (err) *err += "'" + path + "' lies outside the asset root\n";
    return false;
  }
  return tinygltf::ReadWholeFile(out, err, path, nullptr);
}

bool write_nothing(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing is not supported\n";
  return false;
}

std::string trim_lines(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (char& c : s)
    if (c == '\n') c = ';';
  return s;
}

double to_degrees(double rad) { return rad * 180.0 / kPiD; }

float srgb_to_linear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

bool all_finite(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}

// ---- The loader ----

class GltfBuilder {
 public:
  GltfBuilder(std::string path, const tinygltf::Model& model) : path_(std::move(path)), model_(model) {}

  Expected<LoadedScene> build() {
    out_.scene.source = path_;
    GDVR_RETURN_IF_ERROR(check_extensions());
    GDVR_RETURN_IF_ERROR(build_node_graph());
    GDVR_RETURN_IF_ERROR(build_animation_channels());
    GDVR_RETURN_IF_ERROR(instantiate_scene());
    GDVR_RETURN_IF_ERROR(build_tracks());
    if (!has_camera_) GDVR_RETURN_IF_ERROR(frame_default_camera());
    if (out_.scene.emitters.empty())
      warn("no lights and no emissive materials: the scene renders black unless lights are added to it");
    return std::move(out_);
  }

 private:
  Status error(const std::string& what) const { return invalid_argument(path_ + ": " + what); }
  Status unsupported(const std::string& what) const { return unimplemented(path_ + ": " + what); }
  void warn(const std::string& what) { out_.scene.warnings.push_back(path_ + ": " + what); }

  std::string node_label(int n) const {
    const std::string& name = model_.nodes[size_t(n)].name;
    return "nodes[" + std::to_string(n) + "]" + (name.empty() ? "" : " ('" + name + "')");
  }
  std::string mesh_label(int m) const {
    const std::string& name = model_.meshes[size_t(m)].name;
    return "meshes[" + std::to_string(m) + "]" + (name.empty() ? "" : " ('" + name + "')");
  }

  // ---- Extensions ----

  Status check_extensions() {
    static const std::set<std::string> kSupported = {"KHR_lights_punctual", "KHR_materials_emissive_strength"};
    for (const std::string& ext : model_.extensionsRequired)
      if (!kSupported.count(ext)) return unsupported("required extension '" + ext + "' is not supported by gdvr");
    for (const std::string& ext : model_.extensionsUsed)
      if (!kSupported.count(ext)) warn("optional extension '" + ext + "' is ignored");
    return Status::Ok();
  }

  // ---- Accessors ----

  // Reads `accessor` as doubles (normalised integers mapped to [0,1] or [-1,1]
  // as the glTF spec defines), checking types, bounds and finiteness.
  Status read_floats(int index, const std::vector<int>& allowed_types, const std::string& what,
                     std::vector<double>* out, int* components) {
    if (index < 0 || size_t(index) >= model_.accessors.size())
      return error(what + ": accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& acc = model_.accessors[size_t(index)];
    std::string where = what + " (accessors[" + std::to_string(index) + "])";
    if (std::find(allowed_types.begin(), allowed_types.end(), acc.type) == allowed_types.end())
      return error(where + ": unexpected element type");
    const int nc = tinygltf::GetNumComponentsInType(uint32_t(acc.type));
    const int ct = acc.componentType;
    if (ct != TINYGLTF_COMPONENT_TYPE_FLOAT && !acc.normalized)
      return error(where + ": component type must be float (or a normalised integer)");
    if (ct == TINYGLTF_COMPONENT_TYPE_INT || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      return error(where + ": normalised 32-bit integers are not valid glTF");
    *components = nc;
    out->assign(acc.count * size_t(nc), 0.0);
    auto decode = [ct](const unsigned char* p) -> double {
      switch (ct) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: { float f; std::memcpy(&f, p, 4); return f; }
        case TINYGLTF_COMPONENT_TYPE_BYTE: { int8_t v; std::memcpy(&v, p, 1); return std::max(v / 127.0, -1.0); }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return p[0] / 255.0;
        case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; std::memcpy(&v, p, 2); return std::max(v / 32767.0, -1.0); }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p, 2); return v / 65535.0; }
        default: return std::nan("");
      }
    };
    if (acc.bufferView >= 0) {
      const unsigned char* base = nullptr;
      size_t stride = 0;
      if (size_t(acc.bufferView) >= model_.bufferViews.size())
        return error(where + ": bufferView " + std::to_string(acc.bufferView) + " does not exist");
      const int byte_stride = acc.ByteStride(model_.bufferViews[size_t(acc.bufferView)]);
      GDVR_RETURN_IF_ERROR(view_span(acc.bufferView, acc.byteOffset, acc.count, ct, nc, byte_stride, where, &base, &stride));
      const size_t cs = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(ct)));
      for (size_t i = 0; i < acc.count; ++i)
        for (int c = 0; c < nc; ++c) (*out)[i * nc + c] = decode(base + i * stride + size_t(c) * cs);
    }
    if (acc.sparse.isSparse) {
      // Sparse substitution (glTF 3.6.2.3): indices name the elements replaced.
      const size_t n = size_t(std::max(0, acc.sparse.count));
      std::vector<uint32_t> idx;
      GDVR_RETURN_IF_ERROR(read_index_view(acc.sparse.indices.bufferView, size_t(acc.sparse.indices.byteOffset), n,
                                           acc.sparse.indices.componentType, where + " sparse indices", &idx));
      const unsigned char* base = nullptr;
      size_t stride = 0;
      const size_t cs = size_t(tinygltf::GetComponentSizeInBytes(uint32_t(ct)));
      GDVR_RETURN_IF_ERROR(view_span(acc.sparse.values.bufferView, size_t(acc.sparse.values.byteOffset), n, ct, nc,
                                     int(cs) * nc, where + " sparse values", &base, &stride));
      for (size_t k = 0; k < n; ++k) {
        if (idx[k] >= acc.count) return error(where + ": sparse index " + std::to_string(idx[k]) + " out of range");
        for (int c = 0; c < nc; ++c) (*out)[idx[k] * nc + c] = decode(base + k * stride + size_t(c) * cs);
      }
    }
    for (size_t i = 0; i < out->size(); ++i)
      if (!std::isfinite((*out)[i]))
        return error(where + ": element " + std::to_string(i / size_t(nc)) + " is not finite (NaN or Inf)");
    return Status::Ok();
  }

  // Locates `count` elements in a buffer view, checking that they fit.
  Status view_span(int view_index, size_t offset, size_t count, int component_type, int nc, int stride,
                   const std::string& where, const unsigned char** base, size_t* stride_out) {
    if (view_index < 0 || size_t(view_index) >= model_.bufferViews.size())
      return error(where + ": bufferView " + std::to_string(view_index) + " does not exist");
    const tinygltf::BufferView& view = model_.bufferViews[size_t(view_index)];
    if (view.buffer < 0 || size_t(view.buffer) >= model_.buffers.size())
      return error(where + ": buffer " + std::to_string(view.buffer) + " does not exist");
    const tinygltf::Buffer& buf = model_.buffers[size_t(view.buffer)];
    const int cs = tinygltf::GetComponentSizeInBytes(uint32_t(component_type));
    if (cs <= 0 || nc <= 0 || stride <= 0) return error(where + ": invalid component type or byte stride");
    const size_t elem = size_t(cs) * size_t(nc);
    if (count > 0) {
      const size_t need = offset + (count - 1) * size_t(stride) + elem;
      if (need > view.byteLength || view.byteOffset + view.byteLength > buf.data.size())
        return error(where + ": reads past the end of bufferViews[" + std::to_string(view_index) + "] or its buffer" +
                     (buf.data.empty() ? " (buffer '" + buf.uri + "' has no data)" : ""));
    }
    *base = buf.data.data() + view.byteOffset + offset;
    *stride_out = size_t(stride);
    return Status::Ok();
  }

  Status read_index_view(int view_index, size_t offset, size_t count, int ct, const std::string& where,
                         std::vector<uint32_t>* out) {
    if (ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
      return error(where + ": indices must be unsigned byte, short or int");
    const int cs = tinygltf::GetComponentSizeInBytes(uint32_t(ct));
    const unsigned char* base = nullptr;
    size_t stride = 0;
    int view_stride = cs;
    if (view_index >= 0 && size_t(view_index) < model_.bufferViews.size() &&
        model_.bufferViews[size_t(view_index)].byteStride > 0)
      view_stride = int(model_.bufferViews[size_t(view_index)].byteStride);
    GDVR_RETURN_IF_ERROR(view_span(view_index, offset, count, ct, 1, view_stride, where, &base, &stride));
    out->resize(count);
    for (size_t i = 0; i < count; ++i) {
      const unsigned char* p = base + i * stride;
      if (cs == 1) {
        (*out)[i] = p[0];
      } else if (cs == 2) {
        uint16_t v;
        std::memcpy(&v, p, 2);
        (*out)[i] = v;
      } else {
        std::memcpy(&(*out)[i], p, 4);
      }
    }
    return Status::Ok();
  }

  // ---- Node graph ----

  Status build_node_graph() {
    graph_ = std::make_shared<GltfNodeGraph>();
    graph_->nodes.resize(model_.nodes.size());
    for (size_t n = 0; n < model_.nodes.size(); ++n) {
      const tinygltf::Node& src = model_.nodes[n];
      GltfNode& dst = graph_->nodes[n];
      std::string where = node_label(int(n));
      if (!all_finite(src.matrix) || !all_finite(src.translation) || !all_finite(src.rotation) || !all_finite(src.scale))
        return error(where + ": transform is not finite");
      if (!src.matrix.empty()) {
        if (src.matrix.size() != 16) return error(where + ": matrix must have 16 numbers");
        dst.has_matrix = true;
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) dst.matrix.m[r][c] = src.matrix[size_t(c * 4 + r)];  // glTF is column-major
      }
      if (!src.translation.empty()) std::copy(src.translation.begin(), src.translation.end(), dst.translation.begin());
      if (!src.rotation.empty()) std::copy(src.rotation.begin(), src.rotation.end(), dst.rotation.begin());
      if (!src.scale.empty()) std::copy(src.scale.begin(), src.scale.end(), dst.scale.begin());
      for (int child : src.children) {
        if (child < 0 || size_t(child) >= model_.nodes.size())
          return error(where + ": child " + std::to_string(child) + " does not exist");
        if (graph_->nodes[size_t(child)].parent >= 0 || size_t(child) == n)
          return error(node_label(child) + " has more than one parent (glTF nodes form a forest)");
        graph_->nodes[size_t(child)].parent = int(n);
      }
    }
    // A cycle would make every node of it a child: walk up from each node.
    for (size_t n = 0; n < graph_->nodes.size(); ++n) {
      size_t steps = 0;
      for (int p = graph_->nodes[n].parent; p >= 0; p = graph_->nodes[size_t(p)].parent)
        if (++steps > graph_->nodes.size()) return error(node_label(int(n)) + " is part of a cycle in the node hierarchy");
    }
    return Status::Ok();
  }

  Status build_animation_channels() {
    std::set<std::pair<int, int>> seen;  // (node, path)
    size_t playing = 0;
    for (size_t a = 0; a < model_.animations.size(); ++a) {
      const tinygltf::Animation& anim = model_.animations[a];
      std::string aw = "animations[" + std::to_string(a) + "]" + (anim.name.empty() ? "" : " ('" + anim.name + "')");
      if (!anim.channels.empty()) ++playing;
      for (size_t c = 0; c < anim.channels.size(); ++c) {
        const tinygltf::AnimationChannel& ch = anim.channels[c];
        std::string where = aw + ".channels[" + std::to_string(c) + "]";
        if (ch.target_node < 0) continue;  // spec: no node means an extension's target; nothing to animate here
        if (size_t(ch.target_node) >= model_.nodes.size()) return error(where + ": target node does not exist");
        GltfChannel out;
        out.node = ch.target_node;
        if (ch.target_path == "translation") out.path = GltfPath::kTranslation;
        else if (ch.target_path == "rotation") out.path = GltfPath::kRotation;
        else if (ch.target_path == "scale") out.path = GltfPath::kScale;
        else if (ch.target_path == "weights")
          return unsupported(where + ": morph target weights of " + node_label(ch.target_node) +
                             " are animated; morph targets are not supported");
        else return error(where + ": unknown target path '" + ch.target_path + "'");
        if (graph_->nodes[size_t(out.node)].has_matrix)
          return error(where + ": " + node_label(out.node) + " has a matrix; animated nodes must use TRS (glTF 5.25)");
        if (ch.sampler < 0 || size_t(ch.sampler) >= anim.samplers.size()) return error(where + ": sampler does not exist");
        const tinygltf::AnimationSampler& s = anim.samplers[size_t(ch.sampler)];
        std::string sw = aw + ".samplers[" + std::to_string(ch.sampler) + "]";
        if (s.interpolation == "STEP") out.sampler.interpolation = GltfInterpolation::kStep;
        else if (s.interpolation == "LINEAR" || s.interpolation.empty()) out.sampler.interpolation = GltfInterpolation::kLinear;
        else if (s.interpolation == "CUBICSPLINE") out.sampler.interpolation = GltfInterpolation::kCubicSpline;
        else return error(sw + ": unknown interpolation '" + s.interpolation + "'");
        int nc = 0;
        GDVR_RETURN_IF_ERROR(read_floats(s.input, {TINYGLTF_TYPE_SCALAR}, sw + " input", &out.sampler.times, &nc));
        int want = out.path == GltfPath::kRotation ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3;
        GDVR_RETURN_IF_ERROR(read_floats(s.output, {want}, sw + " output", &out.sampler.values, &nc));
        out.sampler.components = nc;
        const size_t keys = out.sampler.times.size();
        const size_t per_key = out.sampler.interpolation == GltfInterpolation::kCubicSpline ? 3 : 1;
        if (keys == 0) return error(sw + ": no keyframes");
        if (out.sampler.values.size() != keys * per_key * size_t(nc))
          return error(sw + ": output has " + std::to_string(out.sampler.values.size() / size_t(nc)) + " elements, expected " +
                       std::to_string(keys * per_key) + " for " + std::to_string(keys) + " keys");
        for (size_t k = 1; k < keys; ++k)
          if (!(out.sampler.times[k] > out.sampler.times[k - 1]))
            return error(sw + ": input times must be strictly increasing (key " + std::to_string(k) + ")");
        if (!seen.insert({out.node, int(out.path)}).second) {
          warn(where + ": " + node_label(out.node) + " " + ch.target_path +
               " is already animated by an earlier channel; this one is ignored");
          continue;
        }
        graph_->channels.push_back(std::move(out));
      }
    }
    if (playing > 1) warn(std::to_string(playing) + " animations play together from t = 0");
    return Status::Ok();
  }

  // ---- Scene instantiation ----

  // Unique ids: shapes, emitters and the camera share one namespace because a
  // track's target matches any of them. "sensor" is the job's camera alias.
  std::string unique_id(const std::string& base) {
    std::string id = base;
    for (int k = 1; used_ids_.count(id); ++k) id = base + "." + std::to_string(k);
    used_ids_.insert(id);
    return id;
  }
  std::string node_base_name(int n) const {
    const std::string& name = model_.nodes[size_t(n)].name;
    return name.empty() ? "node" + std::to_string(n) : name;
  }

  Status instantiate_scene() {
    used_ids_.insert("sensor");
    std::vector<int> roots;
    int scene = model_.defaultScene;
    if (scene < 0 && !model_.scenes.empty()) scene = 0;
    if (scene >= int(model_.scenes.size())) return error("scene " + std::to_string(scene) + " does not exist");
    if (scene >= 0) {
      roots = model_.scenes[size_t(scene)].nodes;
    } else {
      warn("no scene defined: rendering every root node");
      for (size_t n = 0; n < graph_->nodes.size(); ++n)
        if (graph_->nodes[n].parent < 0) roots.push_back(int(n));
    }
    std::vector<int> stack(roots.rbegin(), roots.rend());
    std::set<int> visited;
    while (!stack.empty()) {
      int n = stack.back();
      stack.pop_back();
      if (n < 0 || size_t(n) >= model_.nodes.size()) return error("scene node " + std::to_string(n) + " does not exist");
      if (!visited.insert(n).second) return error(node_label(n) + " is listed twice in the scene");
      GDVR_RETURN_IF_ERROR(instantiate_node(n));
      const auto& children = model_.nodes[size_t(n)].children;
      for (auto it = children.rbegin(); it != children.rend(); ++it) stack.push_back(*it);
    }
    if (out_.scene.shapes.empty()) warn("the scene has no triangle meshes");
    return Status::Ok();
  }

  Status instantiate_node(int n) {
    const tinygltf::Node& node = model_.nodes[size_t(n)];
    if (node.skin >= 0)
      return unsupported(node_label(n) + " uses skins[" + std::to_string(node.skin) + "]: skinning is not supported");
    const Matrix4 world = graph_->world_matrix(n, 0.0);
    const bool animated = graph_->is_animated(n);

    if (node.mesh >= 0) {
      if (size_t(node.mesh) >= model_.meshes.size()) return error(node_label(n) + ": mesh does not exist");
      const tinygltf::Mesh& mesh = model_.meshes[size_t(node.mesh)];
      if (!node.weights.empty() || !mesh.weights.empty())
        return unsupported(node_label(n) + " / " + mesh_label(node.mesh) + ": morph targets are not supported");
      std::string id = unique_id(node_base_name(n));
      bool any = false;
      for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        auto shape_mesh = primitive_mesh(node.mesh, int(p));
        if (!shape_mesh.ok()) return shape_mesh.status();
        if (!shape_mesh.value()) continue;  // nothing left after repair (warned)
        Shape s;
        s.id = id;
        s.mesh = shape_mesh.value();
        s.to_world = gltf_to_transform(world);
        const int material = mesh.primitives[p].material;
        auto bsdf = material_bsdf(material);
        if (!bsdf.ok()) return bsdf.status();
        s.bsdf = bsdf.value();
        Rgb emission = material_emission(material);
        if (!emission.is_black()) {
          Emitter em;
          em.type = EmitterType::kArea;
          em.radiance = emission;
          em.to_world = s.to_world;
          em.shape = int(out_.scene.shapes.size());
          out_.scene.emitters.push_back(em);
          s.emitter = int(out_.scene.emitters.size()) - 1;
        }
        out_.scene.shapes.push_back(std::move(s));
        any = true;
      }
      if (any && animated) animated_targets_.push_back({id, n, Matrix4::identity(), false});
    }

    if (node.camera >= 0) {
      if (size_t(node.camera) >= model_.cameras.size()) return error(node_label(n) + ": camera does not exist");
      GDVR_RETURN_IF_ERROR(build_camera(n, world, animated));
    }

    auto light_ext = node.extensions.find("KHR_lights_punctual");
    if (light_ext != node.extensions.end() && light_ext->second.Has("light")) {
      const tinygltf::Value& v = light_ext->second.Get("light");
      if (!v.IsNumber()) return error(node_label(n) + ": KHR_lights_punctual.light must be an index");
      int light = int(v.GetNumberAsDouble());
      if (light < 0 || size_t(light) >= model_.lights.size())
        return error(node_label(n) + ": light " + std::to_string(light) + " does not exist");
      GDVR_RETURN_IF_ERROR(build_light(n, light, world, animated));
    }
    return Status::Ok();
  }

  // One TriangleMesh per (mesh, primitive), shared by every node instancing it.
  Expected<std::shared_ptr<const TriangleMesh>> primitive_mesh(int mesh_index, int prim_index) {
    auto key = std::make_pair(mesh_index, prim_index);
    auto cached = mesh_cache_.find(key);
    if (cached != mesh_cache_.end()) return cached->second;
    const tinygltf::Primitive& prim = model_.meshes[size_t(mesh_index)].primitives[size_t(prim_index)];
    std::string where = mesh_label(mesh_index) + ".primitives[" + std::to_string(prim_index) + "]";
    if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) {
      static const char* kModes[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP", "TRIANGLES", "TRIANGLE_STRIP", "TRIANGLE_FAN"};
      std::string mode = prim.mode >= 0 && prim.mode <= 6 ? kModes[prim.mode] : std::to_string(prim.mode);
      return unsupported(where + ": primitive mode " + mode + " is not supported (only TRIANGLES)");
    }
    if (!prim.targets.empty()) return unsupported(where + ": morph targets are not supported");
    for (const auto& attr : prim.attributes) {
      if (attr.first.rfind("JOINTS_", 0) == 0 || attr.first.rfind("WEIGHTS_", 0) == 0)
        return unsupported(where + ": skinning attribute " + attr.first + " is not supported");
      if (attr.first == "COLOR_0") warn(where + ": vertex colours (COLOR_0) are ignored");
    }

    TriangleMesh mesh;
    auto attr = [&](const char* name) { auto it = prim.attributes.find(name); return it == prim.attributes.end() ? -1 : it->second; };
    std::vector<double> data;
    int nc = 0;
    if (attr("POSITION") < 0) return error(where + ": no POSITION attribute");
    GDVR_RETURN_IF_ERROR(read_floats(attr("POSITION"), {TINYGLTF_TYPE_VEC3}, where + " POSITION", &data, &nc));
    for (size_t i = 0; i + 2 < data.size(); i += 3) mesh.positions.push_back(Vec3f(float(data[i]), float(data[i + 1]), float(data[i + 2])));
    const size_t n = mesh.positions.size();
    if (attr("NORMAL") >= 0) {
      GDVR_RETURN_IF_ERROR(read_floats(attr("NORMAL"), {TINYGLTF_TYPE_VEC3}, where + " NORMAL", &data, &nc));
      for (size_t i = 0; i + 2 < data.size(); i += 3) mesh.normals.push_back(Vec3f(float(data[i]), float(data[i + 1]), float(data[i + 2])));
      if (mesh.normals.size() != n) return error(where + ": NORMAL count differs from POSITION count");
    }
    if (attr("TEXCOORD_0") >= 0) {
      GDVR_RETURN_IF_ERROR(read_floats(attr("TEXCOORD_0"), {TINYGLTF_TYPE_VEC2}, where + " TEXCOORD_0", &data, &nc));
      // glTF's uv origin is the image's top-left corner, as gdvr's bitmap lookup: no flip.
      for (size_t i = 0; i + 1 < data.size(); i += 2) mesh.uvs.push_back(Vec2f(float(data[i]), float(data[i + 1])));
      if (mesh.uvs.size() != n) return error(where + ": TEXCOORD_0 count differs from POSITION count");
    }
    if (prim.indices >= 0) {
      if (size_t(prim.indices) >= model_.accessors.size()) return error(where + ": indices accessor does not exist");
      const tinygltf::Accessor& acc = model_.accessors[size_t(prim.indices)];
      if (acc.type != TINYGLTF_TYPE_SCALAR || acc.sparse.isSparse || acc.bufferView < 0)
        return error(where + ": indices must be a scalar, non-sparse accessor with a bufferView");
      GDVR_RETURN_IF_ERROR(read_index_view(acc.bufferView, acc.byteOffset, acc.count, acc.componentType,
                                           where + " indices (accessors[" + std::to_string(prim.indices) + "])", &mesh.indices));
    } else {
      mesh.indices.resize(n);
      for (size_t i = 0; i < n; ++i) mesh.indices[i] = uint32_t(i);
    }
    if (mesh.indices.size() % 3 != 0) return error(where + ": index count " + std::to_string(mesh.indices.size()) + " is not a multiple of 3");
    MeshRepairReport report;
    GDVR_RETURN_IF_ERROR(validate_and_repair_mesh(&mesh, path_ + ": " + where, &report));
    if (report.changed()) out_.scene.warnings.push_back(report.describe(path_ + ": " + where));
    std::shared_ptr<const TriangleMesh> result;
    if (mesh.triangle_count() == 0) {
      warn(where + ": no non-degenerate triangles; skipped");
    } else {
      result = std::make_shared<const TriangleMesh>(std::move(mesh));
    }
    mesh_cache_[key] = result;
    return result;
  }

  // ---- Materials ----

  // Decodes image `index` (PNG/JPEG) to 3-channel float, sRGB-decoded unless raw.
  Expected<std::shared_ptr<const Image>> decode_image(int index, bool srgb) {
    auto key = std::make_pair(index, srgb);
    auto cached = image_cache_.find(key);
    if (cached != image_cache_.end()) return cached->second;
    if (index < 0 || size_t(index) >= model_.images.size()) return error("images[" + std::to_string(index) + "] does not exist");
    const tinygltf::Image& img = model_.images[size_t(index)];
    std::string where = "images[" + std::to_string(index) + "]" + (img.uri.empty() ? "" : " ('" + img.uri + "')");
    if (img.image.empty()) return not_found(path_ + ": " + where + ": the image could not be read");
    int w = 0, h = 0, comp = 0;
    const int size = int(img.image.size());
    const bool sixteen = stbi_is_16_bit_from_memory(img.image.data(), size) != 0;
    void* pixels = sixteen ? static_cast<void*>(stbi_load_16_from_memory(img.image.data(), size, &w, &h, &comp, 3))
                           : static_cast<void*>(stbi_load_from_memory(img.image.data(), size, &w, &h, &comp, 3));
    if (!pixels) return error(where + ": cannot decode (" + std::string(stbi_failure_reason()) + ")");
    Image out(w, h, 3);
    const float scale = sixteen ? 1.0f / 65535.0f : 1.0f / 255.0f;
    for (size_t i = 0; i < size_t(w) * size_t(h) * 3; ++i) {
      float v = (sixteen ? float(static_cast<const uint16_t*>(pixels)[i]) : float(static_cast<const uint8_t*>(pixels)[i])) * scale;
      out.data()[i] = srgb ? srgb_to_linear(v) : v;
    }
    stbi_image_free(pixels);
    auto shared = std::make_shared<const Image>(std::move(out));
    image_cache_[key] = shared;
    return shared;
  }

  Expected<std::shared_ptr<const Image>> texture_image(const tinygltf::TextureInfo& info, bool srgb, const std::string& where) {
    if (info.index < 0 || size_t(info.index) >= model_.textures.size())
      return error(where + ": textures[" + std::to_string(info.index) + "] does not exist");
    const tinygltf::Texture& tex = model_.textures[size_t(info.index)];
    if (info.texCoord != 0) warn(where + ": TEXCOORD_" + std::to_string(info.texCoord) + " is not loaded; TEXCOORD_0 used");
    if (info.extensions.count("KHR_texture_transform")) warn(where + ": KHR_texture_transform is ignored");
    if (tex.sampler >= 0 && size_t(tex.sampler) < model_.samplers.size()) {
      const tinygltf::Sampler& s = model_.samplers[size_t(tex.sampler)];
      if ((s.wrapS != -1 && s.wrapS != TINYGLTF_TEXTURE_WRAP_REPEAT) || (s.wrapT != -1 && s.wrapT != TINYGLTF_TEXTURE_WRAP_REPEAT))
        warn(where + ": clamp/mirror wrap modes are rendered as repeat");
    }
    auto img = decode_image(tex.source, srgb);
    if (!img.ok()) return img.status().with_context(where + ": ");
    return img;
  }

  // Mean of one channel (approximating a texture gdvr cannot apply per texel).
  static double channel_mean(const Image& img, int c) {
    double sum = 0;
    for (size_t i = 0; i < img.pixel_count(); ++i) sum += img.data()[i * 3 + size_t(c)];
    return img.pixel_count() ? sum / double(img.pixel_count()) : 0.0;
  }

  // Metallic-roughness onto gdvr's BSDFs (no layered "principled" BSDF exists):
  //   metallic >= 0.5: roughconductor, GGX, alpha = roughness^2, eta/k "none"
  //     (Fresnel = 1) with specular_reflectance = baseColor, i.e. F0 = baseColor
  //     without the edge tint: the usual artist-friendly approximation.
  //   metallic < 0.5: roughplastic, GGX, alpha = roughness^2, diffuse_reflectance
  //     = baseColor, int_ior 1.5 in air (glTF's F0 = 0.04).
  //   alpha < 1e-3: the smooth conductor / plastic.
  // metallicRoughnessTexture is averaged into the factors (warned); alpha
  // (BLEND/MASK) is ignored (warned); doubleSided -> two_sided.
  // No material: glTF's default material (white, metallic 1, roughness 1).
  Expected<int> material_bsdf(int material) {
    auto cached = bsdf_cache_.find(material);
    if (cached != bsdf_cache_.end()) return cached->second;
    Bsdf b;
    Rgb base(1.0f);
    double metallic = 1, roughness = 1;
    Texture base_texture = Texture::constant(base);
    if (material >= 0) {
      if (size_t(material) >= model_.materials.size()) return error("materials[" + std::to_string(material) + "] does not exist");
      const tinygltf::Material& m = model_.materials[size_t(material)];
      std::string where = "materials[" + std::to_string(material) + "]" + (m.name.empty() ? "" : " ('" + m.name + "')");
      const auto& pbr = m.pbrMetallicRoughness;
      if (!all_finite(pbr.baseColorFactor) || !std::isfinite(pbr.metallicFactor) || !std::isfinite(pbr.roughnessFactor) ||
          !all_finite(m.emissiveFactor))
        return error(where + ": a factor is not finite");
      if (pbr.baseColorFactor.size() >= 3) base = Rgb(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]), float(pbr.baseColorFactor[2]));
      metallic = std::clamp(pbr.metallicFactor, 0.0, 1.0);
      roughness = std::clamp(pbr.roughnessFactor, 0.0, 1.0);
      base_texture = Texture::constant(base);
      if (pbr.baseColorTexture.index >= 0) {
        auto img = texture_image(pbr.baseColorTexture, /*srgb=*/true, where + " baseColorTexture");
        if (!img.ok()) return img.status();
        std::shared_ptr<const Image> bitmap = img.value();
        if (base.r != 1.0f || base.g != 1.0f || base.b != 1.0f) {  // bake the factor: gdvr textures have no scale
          Image scaled = *bitmap;
          for (size_t i = 0; i < scaled.pixel_count(); ++i) {
            scaled.data()[i * 3] *= base.r;
            scaled.data()[i * 3 + 1] *= base.g;
            scaled.data()[i * 3 + 2] *= base.b;
          }
          bitmap = std::make_shared<const Image>(std::move(scaled));
        }
        base_texture.type = TextureType::kBitmap;
        base_texture.bitmap = bitmap;
      }
      if (pbr.metallicRoughnessTexture.index >= 0) {
        auto img = texture_image(pbr.metallicRoughnessTexture, /*srgb=*/false, where + " metallicRoughnessTexture");
        if (!img.ok()) return img.status();
        roughness *= channel_mean(*img.value(), 1);  // glTF: G = roughness, B = metalness
        metallic *= channel_mean(*img.value(), 2);
        warn(where + ": metallicRoughnessTexture approximated by its mean (metallic " + std::to_string(metallic) +
             ", roughness " + std::to_string(roughness) + ")");
      }
      if (m.alphaMode != "OPAQUE" && !m.alphaMode.empty()) warn(where + ": alphaMode " + m.alphaMode + " rendered as OPAQUE");
      if (m.normalTexture.index >= 0 || m.occlusionTexture.index >= 0) warn(where + ": normal and occlusion textures are ignored");
      for (const auto& ext : m.extensions)
        if (ext.first != "KHR_materials_emissive_strength") warn(where + ": material extension " + ext.first + " is ignored");
      b.two_sided = m.doubleSided;
    }
    const float alpha = float(roughness * roughness);
    const bool smooth = alpha < kSmoothAlpha;
    b.distribution = MicrofacetType::kGGX;
    b.alpha_u = b.alpha_v = smooth ? 0.0f : alpha;
    if (metallic >= 0.5) {
      b.type = smooth ? BsdfType::kConductor : BsdfType::kRoughConductor;
      b.eta = Rgb(0.0f);
      b.k = Rgb(1.0f);
      b.specular_reflectance = base_texture;
    } else {
      b.type = smooth ? BsdfType::kPlastic : BsdfType::kRoughPlastic;
      b.reflectance = base_texture;
      b.specular_reflectance = Texture::constant(Rgb(1.0f));
      b.int_ior = 1.5f;
      b.ext_ior = 1.0f;
      b.nonlinear = false;
    }
    b.finalize();
    out_.scene.bsdfs.push_back(b);
    int index = int(out_.scene.bsdfs.size()) - 1;
    bsdf_cache_[material] = index;
    return index;
  }

  // emissiveFactor x KHR_materials_emissive_strength (x the emissive texture's
  // mean: area emitters have one radiance). glTF's emission is in nits; with the
  // light conversions below (1 cd -> 1 W/sr) 1 nit -> 1 W/(m^2 sr) keeps ratios.
  Rgb material_emission(int material) {
    if (material < 0 || size_t(material) >= model_.materials.size()) return Rgb(0.0f);
    const tinygltf::Material& m = model_.materials[size_t(material)];
    if (m.emissiveFactor.size() < 3) return Rgb(0.0f);
    Rgb e(float(m.emissiveFactor[0]), float(m.emissiveFactor[1]), float(m.emissiveFactor[2]));
    auto ext = m.extensions.find("KHR_materials_emissive_strength");
    if (ext != m.extensions.end() && ext->second.Has("emissiveStrength")) {
      double strength = ext->second.Get("emissiveStrength").GetNumberAsDouble();
      if (std::isfinite(strength) && strength >= 0) e *= float(strength);
    }
    if (!e.is_black() && m.emissiveTexture.index >= 0) {
      std::string where = "materials[" + std::to_string(material) + "] emissiveTexture";
      auto img = texture_image(m.emissiveTexture, /*srgb=*/true, where);
      if (img.ok()) {
        e *= Rgb(float(channel_mean(*img.value(), 0)), float(channel_mean(*img.value(), 1)), float(channel_mean(*img.value(), 2)));
        if (!emissive_texture_warned_.count(material)) warn(where + ": approximated by its mean colour");
      } else {
        warn(where + ": " + img.status().message() + "; emissiveFactor used alone");
      }
      emissive_texture_warned_.insert(material);
    }
    return e;
  }

  // ---- Cameras and lights ----

  // glTF cameras and lights look along -z with +y up; gdvr's camera looks along
  // +z with +y up and +x to the image's left, its spot and directional emitters
  // point along +z. A half turn about y maps one onto the other and keeps
  // glTF's +x (image right) on gdvr's image right.
  static Matrix4 gltf_to_gdvr_frame() {
    Matrix4 m = Matrix4::identity();
    m.m[0][0] = -1;
    m.m[2][2] = -1;
    return m;
  }

  Status build_camera(int n, const Matrix4& world, bool animated) {
    const tinygltf::Camera& cam = model_.cameras[size_t(model_.nodes[size_t(n)].camera)];
    std::string where = node_label(n) + " camera";
    if (cam.type == "orthographic") return unsupported(where + ": orthographic cameras are not supported");
    if (cam.type != "perspective") return error(where + ": unknown camera type '" + cam.type + "'");
    if (has_camera_) {
      warn(where + ": ignored (gdvr renders the first camera of the scene)");
      return Status::Ok();
    }
    const tinygltf::PerspectiveCamera& p = cam.perspective;
    if (!(p.yfov > 0 && p.yfov < kPiD)) return error(where + ": yfov must be in (0, pi)");
    if (!(p.znear > 0) || !std::isfinite(p.znear)) return error(where + ": znear must be positive");
    if (!(p.zfar >= 0) || !std::isfinite(p.zfar) || (p.zfar > 0 && p.zfar <= p.znear))
      return error(where + ": zfar must be greater than znear (or absent)");
    Camera& c = out_.scene.camera;
    c.id = unique_id(node_base_name(n) + (model_.nodes[size_t(n)].mesh >= 0 ? ".camera" : ""));
    c.fov = float(to_degrees(p.yfov));
    c.fov_axis = FovAxis::kY;
    c.near_clip = float(p.znear);
    if (p.zfar > 0) c.far_clip = float(p.zfar);
    // The film's aspect comes from the job; the camera's own aspect only sets
    // the default film height.
    if (p.aspectRatio > 0 && std::isfinite(p.aspectRatio))
      out_.scene.defaults.height = std::max(1, int(std::lround(out_.scene.defaults.width / p.aspectRatio)));
    c.to_world = gltf_to_transform(gltf_remove_scale(world) * gltf_to_gdvr_frame());
    has_camera_ = true;
    if (animated) animated_targets_.push_back({c.id, n, gltf_to_gdvr_frame(), true});
    return Status::Ok();
  }

  // Photometric to gdvr units: gdvr renders relative linear RGB, so 1 cd is
  // taken as 1 W/sr (point, spot), 1 lx as 1 W/m^2 (directional) and emission
  // as 1 W/(m^2 sr) per nit. That drops the constant 683 lm/W (and the
  // luminous efficacy of the spectrum) from every light alike, so relative
  // brightness matches a glTF viewer's and exposure absorbs the constant.
  Status build_light(int n, int light_index, const Matrix4& world, bool animated) {
    const tinygltf::Light& l = model_.lights[size_t(light_index)];
    std::string where = node_label(n) + " light " + std::to_string(light_index) + (l.name.empty() ? "" : " ('" + l.name + "')");
    Rgb color(1.0f);
    if (!l.color.empty()) {
      if (l.color.size() != 3 || !all_finite(l.color)) return error(where + ": color must be three finite numbers");
      color = Rgb(float(l.color[0]), float(l.color[1]), float(l.color[2]));
    }
    if (!std::isfinite(l.intensity) || l.intensity < 0) return error(where + ": intensity must be finite and >= 0");
    Rgb power = color * float(l.intensity);
    Emitter em;
    if (l.type == "point") {
      em.type = EmitterType::kPoint;
      em.intensity = power;
    } else if (l.type == "spot") {
      em.type = EmitterType::kSpot;
      em.intensity = power;
      double outer = l.spot.outerConeAngle, inner = l.spot.innerConeAngle;
      if (!(outer > 0 && outer <= kPiD / 2) || !(inner >= 0 && inner < outer))
        return error(where + ": spot cone angles must satisfy 0 <= inner < outer <= pi/2");
      // glTF's smooth falloff between the cones becomes Mitsuba's linear-in-angle one.
      em.cutoff_angle = float(to_degrees(outer));
      em.beam_width = float(to_degrees(inner));
    } else if (l.type == "directional") {
      em.type = EmitterType::kDirectional;
      em.irradiance = power;
    } else {
      return error(where + ": unknown light type '" + l.type + "'");
    }
    if (l.range > 0) warn(where + ": range is ignored (gdvr lights fall off with the inverse square only)");
    em.id = unique_id(node_base_name(n) + (model_.nodes[size_t(n)].mesh >= 0 ? ".light" : ""));
    em.to_world = gltf_to_transform(gltf_remove_scale(world) * gltf_to_gdvr_frame());
    out_.scene.emitters.push_back(em);
    if (animated) animated_targets_.push_back({em.id, n, gltf_to_gdvr_frame(), true});
    return Status::Ok();
  }

  // ---- Animation tracks ----

  struct AnimatedTarget {
    std::string id;
    int node;
    Matrix4 offset;
    bool rigid;
  };

  Status build_tracks() {
    for (const AnimatedTarget& t : animated_targets_) {
      Track track;
      track.target = t.id;
      track.interpolation = Interpolation::kLinear;
      track.curve = std::make_shared<GltfNodeCurve>(graph_, t.node, t.offset, t.rigid);
      for (double time : graph_->key_times(t.node)) {
        Keyframe k;
        k.time = time;
        k.to_world = track.curve->evaluate(time);
        track.keys.push_back(k);
      }
      if (track.keys.empty()) track.keys.push_back(Keyframe{0.0, track.curve->evaluate(0.0)});
      out_.animation.tracks.push_back(std::move(track));
    }
    return Status::Ok();
  }

  // ---- Default camera ----

  Status frame_default_camera() {
    Vec3f lo(std::numeric_limits<float>::infinity()), hi(-std::numeric_limits<float>::infinity());
    for (const Shape& s : out_.scene.shapes)
      for (const Vec3f& p : s.mesh->positions) {
        Vec3f w = s.to_world.point(p);
        lo = Vec3f(std::min(lo.x, w.x), std::min(lo.y, w.y), std::min(lo.z, w.z));
        hi = Vec3f(std::max(hi.x, w.x), std::max(hi.y, w.y), std::max(hi.z, w.z));
      }
    Vec3f center(0.0f);
    float radius = 1.0f;
    if (!out_.scene.shapes.empty()) {
      center = (lo + hi) * 0.5f;
      radius = std::max(0.5f * length(hi - lo), 1e-3f);
    }
    Camera& c = out_.scene.camera;
    c.id.clear();
    c.fov = 40.0f;
    c.fov_axis = FovAxis::kSmaller;  // the bounding sphere fits whatever the film's aspect
    const float distance = radius / std::sin(radians(c.fov) * 0.5f) * 1.05f;
    // Looks down glTF's -z from +z, +y up: how glTF viewers show a model by default.
    if (!Transform::look_at(center + Vec3f(0, 0, distance), center, Vec3f(0, 1, 0), &c.to_world))
      return error("cannot place the default camera");
    c.near_clip = std::max(1e-4f, (distance - radius) * 0.01f);
    c.far_clip = (distance + radius) * 4.0f;
    warn("no camera in the file: a default camera frames the bounding box at t = 0 (a job's 'sensor' track replaces it)");
    return Status::Ok();
  }

  std::string path_;
  const tinygltf::Model& model_;
  LoadedScene out_;
  std::shared_ptr<GltfNodeGraph> graph_;
  std::set<std::string> used_ids_;
  std::map<std::pair<int, int>, std::shared_ptr<const TriangleMesh>> mesh_cache_;
  std::map<std::pair<int, bool>, std::shared_ptr<const Image>> image_cache_;
  std::map<int, int> bsdf_cache_;
  std::set<int> emissive_texture_warned_;
  std::vector<AnimatedTarget> animated_targets_;
  bool has_camera_ = false;
};

}  // namespace

Expected<LoadedScene> load_gltf_scene(const std::string& path, const LoadOptions& options) {
  if (!options.params.empty())
    return invalid_argument(path + ": scene parameters (params / -D) apply to Mitsuba XML scenes only");
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return not_found(path + ": no such file");
  if (!options.asset_root.empty() && !is_inside_root(path, options.asset_root))
    return invalid_argument(path + ": lies outside the asset root");

  // .glb by content, not extension: a binary file named .gltf still loads.
  bool binary = false;
  {
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {0, 0, 0, 0};
    in.read(magic, 4);
    binary = in.gcount() == 4 && std::string(magic, 4) == "glTF";
  }

  FsContext ctx{options.asset_root};
  tinygltf::FsCallbacks callbacks{&file_exists, &expand_nothing, &read_whole_file, &write_nothing, &ctx};
  tinygltf::TinyGLTF parser;
  parser.SetFsCallbacks(callbacks);
  parser.SetImageLoader(&keep_encoded_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  bool ok = binary ? parser.LoadBinaryFromFile(&model, &err, &warn, path) : parser.LoadASCIIFromFile(&model, &err, &warn, path);
  if (!ok) {
    std::string what = trim_lines(err.empty() ? warn : err);
    // A referenced file that is missing is "not found"; everything else is a malformed file.
    bool missing = what.find("File not found") != std::string::npos || what.find("Failed to load external") != std::string::npos ||
                   what.find("asset root") != std::string::npos;
    Status st(missing ? StatusCode::kNotFound : StatusCode::kInvalidArgument, path + ": cannot load glTF: " + what);
    return st;
  }
  GltfBuilder builder(path, model);
  auto loaded = builder.build();
  if (!loaded.ok()) return loaded.status();
  if (!warn.empty()) loaded->scene.warnings.insert(loaded->scene.warnings.begin(), path + ": " + trim_lines(warn));
  return loaded;
}

}  // namespace gdvr
