// Second stage of Mitsuba scene loading: the element tree of mitsuba_xml.h
// becomes a Scene. One build_* function per plugin kind; each reads its
// parameters through MitsubaProps, which reports anything left unread.
#include "core/scene/mitsuba_loader.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/bsdf/conductor_presets.h"
#include "core/io/image_io.h"
#include "core/scene/ior_table.h"
#include "core/scene/mesh_repair.h"
#include "core/scene/mitsuba_props.h"
#include "core/scene/mitsuba_xml.h"
#include "core/scene/obj_reader.h"
#include "core/scene/ply_reader.h"
#include "core/scene/serialized_reader.h"
#include "core/scene/shape_tessellation.h"
#include "core/scene/spectrum_to_rgb.h"
#include "core/util/path_confinement.h"

namespace gdvr {

namespace fs = std::filesystem;

namespace {

constexpr int kDiskSegments = 256;

bool one_of(const std::string& s, std::initializer_list<const char*> list) {
  for (const char* x : list)
    if (s == x) return true;
  return false;
}

// Plugins that exist in Mitsuba 3 but not in gdvr: UNIMPLEMENTED rather than
// INVALID_ARGUMENT, so that a user knows the file is fine and gdvr is the limit.
bool is_known_mitsuba_plugin(const std::string& kind, const std::string& type) {
  if (kind == "bsdf")
    return one_of(type, {"principled", "principledthin", "blendbsdf", "mask", "bumpmap", "normalmap", "measured",
                         "pplastic", "polarizer", "retarder", "circular", "null", "hair"});
  if (kind == "shape") return one_of(type, {"cylinder", "instance", "shapegroup", "bsplinecurve", "linearcurve", "sdfgrid", "ellipsoids"});
  if (kind == "emitter") return one_of(type, {"projector", "sunsky"});
  if (kind == "texture") return one_of(type, {"mesh_attribute", "volume"});
  if (kind == "sensor") return one_of(type, {"thinlens", "orthographic", "radiancemeter", "irradiancemeter", "distant", "batch"});
  if (kind == "film") return one_of(type, {"specfilm"});
  return false;
}

Status unknown_plugin(const XmlElement& e) {
  std::string type = e.attr("type");
  if (is_known_mitsuba_plugin(e.tag, type))
    return Status(StatusCode::kUnimplemented, e.where() + ": " + e.tag + " type '" + type + "' is not supported by gdvr");
  return e.error("unknown " + e.tag + " type '" + type + "'");
}

UvTransform to_uv_transform(const Matrix4& m) {
  // Mitsuba reads a 2D transform from the 4x4 one: the upper-left 2x2 block and
  // the translation column.
  UvTransform t;
  t.a = float(m.m[0][0]);
  t.b = float(m.m[0][1]);
  t.c = float(m.m[0][3]);
  t.d = float(m.m[1][0]);
  t.e = float(m.m[1][1]);
  t.f = float(m.m[1][3]);
  return t;
}

class SceneBuilder {
 public:
  SceneBuilder(const XmlDocument& doc, const LoadOptions& options, std::string base_dir)
      : doc_(doc), options_(options), base_dir_(std::move(base_dir)) {
    scene_.source = doc.root.source ? doc.root.source->path : std::string();
  }

  Expected<Scene> build() {
    scene_.warnings = doc_.warnings;
    GDVR_RETURN_IF_ERROR(index_ids(doc_.root));
    bool have_sensor = false, have_integrator = false;
    for (const XmlElement& e : doc_.root.children) {
      if (is_plugin_tag(e.tag)) {
        for (const auto& a : e.attrs)
          if (a.first != "type" && a.first != "id") return e.error("unknown attribute '" + a.first + "' of <" + e.tag + ">");
        if (!e.find_attr("type")) return e.error("<" + e.tag + "> needs a 'type'");
      }
      if (e.tag == "bsdf") {
        Expected<int> idx = bsdf_index(e);
        if (!idx.ok()) return idx.status();
      } else if (e.tag == "texture") {
        Texture t;
        GDVR_RETURN_IF_ERROR(texture_of(e, &t));
      } else if (e.tag == "emitter") {
        if (e.attr("type") == "area") {
          // A top-level area emitter only exists attached to the shapes that reference it.
          if (!e.find_attr("id")) return e.error("an area emitter must be nested in a <shape> or have an id that shapes reference");
          Emitter em;
          GDVR_RETURN_IF_ERROR(build_emitter(e, &em));
          continue;
        }
        Emitter em;
        GDVR_RETURN_IF_ERROR(build_emitter(e, &em));
        scene_.emitters.push_back(em);
      } else if (e.tag == "shape") {
        GDVR_RETURN_IF_ERROR(build_shape(e));
      } else if (e.tag == "sensor") {
        if (have_sensor) {
          scene_.warnings.push_back(e.where() + ": more than one sensor; gdvr renders the first");
          continue;
        }
        GDVR_RETURN_IF_ERROR(build_sensor(e));
        have_sensor = true;
      } else if (e.tag == "integrator") {
        if (have_integrator) return e.error("more than one <integrator>");
        GDVR_RETURN_IF_ERROR(build_integrator(e));
        have_integrator = true;
      } else if (is_plugin_tag(e.tag)) {
        return Status(StatusCode::kUnimplemented, e.where() + ": top-level <" + e.tag + "> is not supported by gdvr");
      } else {
        return e.error("unexpected <" + e.tag + "> at scene level");
      }
    }
    for (const auto& [id, used] : area_emitter_used_)
      if (!used) scene_.warnings.push_back("area emitter '" + id + "' is not referenced by any shape and emits nothing");
    GDVR_RETURN_IF_ERROR(check_defaults());
    return std::move(scene_);
  }

 private:
  // ---- Ids and references ----

  Status index_ids(const XmlElement& e) {
    for (const XmlElement& c : e.children) {
      if (c.tag != "ref" && c.find_attr("id")) {
        std::string id = c.attr("id");
        auto [it, inserted] = ids_.emplace(id, &c);
        if (!inserted) return c.error("duplicate id '" + id + "' (first defined at " + it->second->where() + ")");
        if (c.tag == "emitter" && c.attr("type") == "area" && &e == &doc_.root) area_emitter_used_[id] = false;
      }
      GDVR_RETURN_IF_ERROR(index_ids(c));
    }
    return Status::Ok();
  }

  // The element a <ref> points to, or `e` itself when it is not a ref.
  Expected<const XmlElement*> deref(const XmlElement& e) {
    if (e.tag != "ref") return &e;
    std::string id = e.attr("id");
    auto it = ids_.find(id);
    if (it == ids_.end()) return Status(StatusCode::kNotFound, e.where() + ": <ref id=\"" + id + "\"> names no object");
    return it->second;
  }

  // ---- Textures ----

  // A texture-valued parameter: constant from <rgb>/<spectrum>/<float>, or a
  // nested or referenced <texture>. Absent: *out untouched.
  Status get_texture(MitsubaProps& props, const std::string& name, Texture* out) {
    const XmlElement* c = props.take(name);
    if (!c) return Status::Ok();
    if (one_of(c->tag, {"rgb", "spectrum", "float"})) {
      Rgb v;
      GDVR_RETURN_IF_ERROR(color_value(*c, spectrum_role(name, /* within_emitter = */ false), &v));
      *out = Texture::constant(v);
      return Status::Ok();
    }
    Expected<const XmlElement*> target = deref(*c);
    if (!target.ok()) return target.status();
    if ((*target)->tag != "texture")
      return props.error(*c, "parameter '" + name + "' must be a colour or a <texture>, not <" + (*target)->tag + ">");
    return texture_of(**target, out);
  }

  // A colour-valued parameter (<rgb>, <spectrum>, <float>) as Mitsuba's RGB
  // variants read it (spectrum_to_rgb.h). Absent: *out untouched.
  Status get_color(MitsubaProps& props, const std::string& name, bool within_emitter, Rgb* out) {
    Expected<const XmlElement*> c = props.take_color(name);
    if (!c.ok()) return c.status();
    if (!*c) return Status::Ok();
    return color_value(**c, spectrum_role(name, within_emitter), out);
  }

  Status color_value(const XmlElement& c, SpectrumRole role, Rgb* out) {
    const std::string* filename = c.tag == "spectrum" ? c.find_attr("filename") : nullptr;
    if (!filename) return parse_rgb_value(c, role, out);
    Expected<std::string> path = resolve(*filename, c);
    if (!path.ok()) return path.status();
    std::ifstream in(*path, std::ios::binary);
    if (!in) return Status(StatusCode::kNotFound, c.where() + ": cannot read spectrum file '" + *filename + "'");
    std::ostringstream text;
    text << in.rdbuf();
    std::vector<double> wavelengths, values;
    GDVR_RETURN_IF_ERROR(parse_spd(text.str(), *filename, &wavelengths, &values));
    Expected<Rgb> rgb = spectrum_list_to_rgb(wavelengths, values, role);
    if (!rgb.ok()) return c.error(rgb.status().message());
    *out = *rgb;
    return Status::Ok();
  }

  Status texture_of(const XmlElement& e, Texture* out) {
    std::string id = e.attr("id");
    if (!id.empty()) {
      auto it = texture_cache_.find(id);
      if (it != texture_cache_.end()) {
        *out = it->second;
        return Status::Ok();
      }
    }
    GDVR_RETURN_IF_ERROR(build_texture(e, out));
    if (!id.empty()) texture_cache_[id] = *out;
    return Status::Ok();
  }

  Status build_texture(const XmlElement& e, Texture* out) {
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    std::string type = e.attr("type");
    Texture t;
    Matrix4 to_uv = Matrix4::identity();
    GDVR_RETURN_IF_ERROR(props.get_matrix("to_uv", &to_uv));
    t.to_uv = to_uv_transform(to_uv);
    if (type == "bitmap") {
      t.type = TextureType::kBitmap;
      std::string filename, filter_type = "bilinear", wrap_mode = "repeat", format;
      bool raw = false;
      GDVR_RETURN_IF_ERROR(props.get_string("filename", &filename));
      GDVR_RETURN_IF_ERROR(props.get_bool("raw", &raw));
      GDVR_RETURN_IF_ERROR(props.get_string("filter_type", &filter_type));
      GDVR_RETURN_IF_ERROR(props.get_string("wrap_mode", &wrap_mode));
      GDVR_RETURN_IF_ERROR(props.get_string("format", &format));
      if (filename.empty()) return props.error(e, "needs a 'filename'");
      // Mitsuba 0.x also had mip-mapped lookups; gdvr has none (nor does Mitsuba 3).
      bool legacy_filter = e.from_legacy_file() && one_of(filter_type, {"trilinear", "ewa"});
      if (!one_of(filter_type, {"bilinear", "nearest"}) && !legacy_filter)
        return props.error(e, "filter_type must be bilinear or nearest");
      if (!one_of(wrap_mode, {"repeat", "mirror", "clamp"})) return props.error(e, "wrap_mode must be repeat, mirror or clamp");
      if (legacy_filter)
        scene_.warnings.push_back(e.where() + ": bitmap filter_type '" + filter_type + "' rendered as bilinear");
      t.filter = filter_type == "nearest" ? TextureFilter::kNearest : TextureFilter::kBilinear;
      t.wrap = wrap_mode == "mirror" ? TextureWrap::kMirror
                                     : (wrap_mode == "clamp" ? TextureWrap::kClamp : TextureWrap::kRepeat);
      Expected<std::string> path = resolve(filename, e);
      if (!path.ok()) return path.status();
      Expected<Image> img = read_rgb_image(*path, raw);
      if (!img.ok()) return img.status().with_context(e.where() + ": ");
      t.bitmap = std::make_shared<const Image>(std::move(*img));
    } else if (type == "checkerboard") {
      t.type = TextureType::kCheckerboard;
      GDVR_RETURN_IF_ERROR(get_color(props, "color0", false, &t.color0));
      GDVR_RETURN_IF_ERROR(get_color(props, "color1", false, &t.color1));
    } else {
      return unknown_plugin(e);
    }
    GDVR_RETURN_IF_ERROR(props.check_all_used());
    *out = t;
    return Status::Ok();
  }

  // ---- BSDFs ----

  Expected<int> bsdf_index(const XmlElement& ref_or_bsdf) {
    Expected<const XmlElement*> target = deref(ref_or_bsdf);
    if (!target.ok()) return target.status();
    const XmlElement& e = **target;
    if (e.tag != "bsdf") return ref_or_bsdf.error("expected a <bsdf>, but id '" + e.attr("id") + "' is a <" + e.tag + ">");
    std::string id = e.attr("id");
    if (!id.empty()) {
      auto it = bsdf_cache_.find(id);
      if (it != bsdf_cache_.end()) return it->second;
    }
    Bsdf b;
    GDVR_RETURN_IF_ERROR(build_bsdf(e, &b, 0));
    scene_.bsdfs.push_back(b);
    int idx = int(scene_.bsdfs.size()) - 1;
    if (!id.empty()) bsdf_cache_[id] = idx;
    return idx;
  }

  Status get_ior(MitsubaProps& props, const std::string& name, float* out) {
    const XmlElement* c = props.take(name);
    if (!c) return Status::Ok();
    if (c->tag == "string") {
      std::string v = c->attr("value");
      if (!lookup_ior(v, out)) return props.error(*c, "unknown IOR name '" + v + "' for '" + name + "'");
      return Status::Ok();
    }
    if (c->tag != "float" && c->tag != "integer")
      return props.error(*c, "parameter '" + name + "' must be <float> or <string>, not <" + c->tag + ">");
    std::vector<double> v;
    GDVR_RETURN_IF_ERROR(parse_float_list(*c, "value", c->attr("value"), &v));
    if (v.size() != 1 || !(v[0] > 0)) return props.error(*c, "'" + name + "' must be one positive number");
    *out = float(v[0]);
    return Status::Ok();
  }

  Status get_microfacet(MitsubaProps& props, Bsdf* b, bool anisotropic) {
    std::string dist = "beckmann";
    GDVR_RETURN_IF_ERROR(props.get_string("distribution", &dist));
    if (dist == "beckmann") b->distribution = MicrofacetType::kBeckmann;
    else if (dist == "ggx") b->distribution = MicrofacetType::kGGX;
    else return props.error(props.plugin(), "distribution must be beckmann or ggx, not '" + dist + "'");
    float alpha = 0.1f;
    GDVR_RETURN_IF_ERROR(props.get_float("alpha", &alpha));
    b->alpha_u = b->alpha_v = alpha;
    if (anisotropic && (props.has("alpha_u") || props.has("alpha_v"))) {
      if (props.has("alpha")) return props.error(props.plugin(), "give either alpha or alpha_u/alpha_v, not both");
      if (!props.has("alpha_u") || !props.has("alpha_v")) return props.error(props.plugin(), "alpha_u and alpha_v go together");
      GDVR_RETURN_IF_ERROR(props.get_float("alpha_u", &b->alpha_u));
      GDVR_RETURN_IF_ERROR(props.get_float("alpha_v", &b->alpha_v));
    }
    if (!(b->alpha_u >= 0) || !(b->alpha_v >= 0)) return props.error(props.plugin(), "roughness alpha must be >= 0");
    GDVR_RETURN_IF_ERROR(props.get_bool("sample_visible", &b->sample_visible));
    return Status::Ok();
  }

  Status build_bsdf(const XmlElement& e, Bsdf* out, int depth) {
    if (depth > 8) return e.error("BSDFs nested too deeply (reference cycle?)");
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    std::string type = e.attr("type");
    Bsdf b;
    if (type == "twosided") {
      std::vector<const XmlElement*> nested = props.take_unnamed();
      for (const char* n : {"bsdf", "bsdf_0", "bsdf_1"})
        if (const XmlElement* c = props.take(n)) nested.push_back(c);
      if (nested.empty()) return props.error(e, "needs a nested <bsdf>");
      if (nested.size() > 2) return props.error(e, "takes one or two nested BSDFs");
      const XmlElement* first = nullptr;
      for (const XmlElement* c : nested) {
        Expected<const XmlElement*> t = deref(*c);
        if (!t.ok()) return t.status();
        if ((*t)->tag != "bsdf") return props.error(*c, "nested <" + (*t)->tag + "> is not a BSDF");
        if (first && *t != first)
          return Status(StatusCode::kUnimplemented,
                        c->where() + ": twosided with different front and back BSDFs is not supported by gdvr");
        first = *t;
      }
      GDVR_RETURN_IF_ERROR(build_bsdf(*first, &b, depth + 1));
      b.two_sided = true;
    } else if (type == "diffuse") {
      b.type = BsdfType::kDiffuse;
      GDVR_RETURN_IF_ERROR(get_texture(props, "reflectance", &b.reflectance));
    } else if (type == "conductor" || type == "roughconductor") {
      b.type = type == "conductor" ? BsdfType::kConductor : BsdfType::kRoughConductor;
      std::string material = "none";
      bool named = props.has("material");
      GDVR_RETURN_IF_ERROR(props.get_string("material", &material));
      if (named && (props.has("eta") || props.has("k"))) return props.error(e, "give either 'material' or eta/k, not both");
      if (!lookup_conductor(material, &b.eta, &b.k)) return props.error(e, "unknown conductor material '" + material + "'");
      GDVR_RETURN_IF_ERROR(get_color(props, "eta", false, &b.eta));
      GDVR_RETURN_IF_ERROR(get_color(props, "k", false, &b.k));
      if (e.from_legacy_file() && props.has("ext_eta")) {
        // Mitsuba 0.x conductors took the exterior's IOR and divided eta and k
        // by it; Mitsuba 3 dropped the parameter (its exterior is vacuum).
        float ext_eta = 1.0f;
        GDVR_RETURN_IF_ERROR(get_ior(props, "ext_eta", &ext_eta));
        b.eta = b.eta / Rgb(ext_eta);
        b.k = b.k / Rgb(ext_eta);
      }
      GDVR_RETURN_IF_ERROR(get_texture(props, "specular_reflectance", &b.specular_reflectance));
      if (type == "roughconductor") GDVR_RETURN_IF_ERROR(get_microfacet(props, &b, /*anisotropic=*/true));
    } else if (type == "plastic" || type == "roughplastic") {
      b.type = type == "plastic" ? BsdfType::kPlastic : BsdfType::kRoughPlastic;
      b.int_ior = 1.49f;  // polypropylene
      b.ext_ior = 1.000277f;
      GDVR_RETURN_IF_ERROR(get_texture(props, "diffuse_reflectance", &b.reflectance));
      GDVR_RETURN_IF_ERROR(get_texture(props, "specular_reflectance", &b.specular_reflectance));
      GDVR_RETURN_IF_ERROR(get_ior(props, "int_ior", &b.int_ior));
      GDVR_RETURN_IF_ERROR(get_ior(props, "ext_ior", &b.ext_ior));
      GDVR_RETURN_IF_ERROR(props.get_bool("nonlinear", &b.nonlinear));
      if (type == "roughplastic") GDVR_RETURN_IF_ERROR(get_microfacet(props, &b, /*anisotropic=*/false));
    } else if (type == "dielectric" || type == "roughdielectric" || type == "thindielectric") {
      b.type = type == "dielectric" ? BsdfType::kDielectric
                                    : (type == "roughdielectric" ? BsdfType::kRoughDielectric : BsdfType::kThinDielectric);
      b.int_ior = 1.5046f;  // bk7, Mitsuba's default glass
      b.ext_ior = 1.000277f;
      GDVR_RETURN_IF_ERROR(get_ior(props, "int_ior", &b.int_ior));
      GDVR_RETURN_IF_ERROR(get_ior(props, "ext_ior", &b.ext_ior));
      GDVR_RETURN_IF_ERROR(get_texture(props, "specular_reflectance", &b.specular_reflectance));
      GDVR_RETURN_IF_ERROR(get_texture(props, "specular_transmittance", &b.specular_transmittance));
      if (type == "roughdielectric") GDVR_RETURN_IF_ERROR(get_microfacet(props, &b, /*anisotropic=*/true));
    } else {
      return unknown_plugin(e);
    }
    GDVR_RETURN_IF_ERROR(props.check_all_used());
    b.finalize();
    *out = b;
    return Status::Ok();
  }

  // ---- Emitters ----

  Status build_emitter(const XmlElement& e, Emitter* out) {
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    std::string type = e.attr("type");
    Emitter em;
    em.id = e.attr("id");
    if (type == "area") {
      em.type = EmitterType::kArea;
      GDVR_RETURN_IF_ERROR(get_color(props, "radiance", true, &em.radiance));
    } else if (type == "point") {
      em.type = EmitterType::kPoint;
      if (props.has("position") && props.has("to_world")) return props.error(e, "give either 'position' or 'to_world', not both");
      Vec3f pos;
      if (props.has("position")) {
        GDVR_RETURN_IF_ERROR(props.get_point("position", &pos));
        em.to_world = Transform::translate(pos);
      }
      GDVR_RETURN_IF_ERROR(props.get_transform("to_world", &em.to_world));
      GDVR_RETURN_IF_ERROR(get_color(props, "intensity", true, &em.intensity));
    } else if (type == "spot") {
      em.type = EmitterType::kSpot;
      GDVR_RETURN_IF_ERROR(props.get_transform("to_world", &em.to_world));
      GDVR_RETURN_IF_ERROR(get_color(props, "intensity", true, &em.intensity));
      GDVR_RETURN_IF_ERROR(props.get_float("cutoff_angle", &em.cutoff_angle));
      em.beam_width = em.cutoff_angle * 0.75f;
      GDVR_RETURN_IF_ERROR(props.get_float("beam_width", &em.beam_width));
      if (!(em.cutoff_angle > 0 && em.cutoff_angle <= 90)) return props.error(e, "cutoff_angle must be in (0, 90] degrees");
      if (!(em.beam_width > 0 && em.beam_width <= em.cutoff_angle))
        return props.error(e, "beam_width must be in (0, cutoff_angle]");
    } else if (type == "directional") {
      em.type = EmitterType::kDirectional;
      if (props.has("direction") && props.has("to_world")) return props.error(e, "give either 'direction' or 'to_world', not both");
      if (props.has("direction")) {
        Vec3f d;
        const XmlElement* at = props.take("direction");
        GDVR_RETURN_IF_ERROR(point_of(*at, &d));
        if (length_squared(d) == 0.0f) return props.error(*at, "direction must be non-zero");
        d = normalize(d);
        Vec3f up = std::abs(d.y) < 0.9f ? Vec3f(0, 1, 0) : Vec3f(1, 0, 0);
        if (!Transform::look_at(Vec3f(0.0f), d, up, &em.to_world)) return props.error(*at, "degenerate direction");
      }
      GDVR_RETURN_IF_ERROR(props.get_transform("to_world", &em.to_world));
      GDVR_RETURN_IF_ERROR(get_color(props, "irradiance", true, &em.irradiance));
    } else if (type == "constant") {
      em.type = EmitterType::kConstant;
      GDVR_RETURN_IF_ERROR(get_color(props, "radiance", true, &em.radiance));
    } else if (type == "envmap") {
      em.type = EmitterType::kEnvmap;
      std::string filename;
      bool mis_compensation = false;
      GDVR_RETURN_IF_ERROR(props.get_string("filename", &filename));
      GDVR_RETURN_IF_ERROR(props.get_float("scale", &em.scale));
      GDVR_RETURN_IF_ERROR(props.get_transform("to_world", &em.to_world));
      GDVR_RETURN_IF_ERROR(props.get_bool("mis_compensation", &mis_compensation));
      if (filename.empty()) return props.error(e, "needs a 'filename'");
      if (mis_compensation) scene_.warnings.push_back(e.where() + ": envmap mis_compensation is ignored");
      Expected<std::string> path = resolve(filename, e);
      if (!path.ok()) return path.status();
      Expected<Image> img = read_rgb_image(*path, /*raw=*/true);
      if (!img.ok()) return img.status().with_context(e.where() + ": ");
      if (img->width() < 2 || img->height() < 1) return props.error(e, "environment map is empty");
      em.envmap = std::make_shared<const Image>(std::move(*img));
    } else {
      return unknown_plugin(e);
    }
    GDVR_RETURN_IF_ERROR(props.check_all_used());
    *out = em;
    return Status::Ok();
  }

  static Status point_of(const XmlElement& e, Vec3f* out) {
    if (e.tag != "point" && e.tag != "vector") return e.error("expected <point> or <vector>, not <" + e.tag + ">");
    if (const std::string* v = e.find_attr("value")) {
      std::vector<double> xs;
      GDVR_RETURN_IF_ERROR(parse_float_list(e, "value", *v, &xs));
      if (xs.size() != 3) return e.error("needs 3 numbers");
      *out = Vec3f(float(xs[0]), float(xs[1]), float(xs[2]));
      return Status::Ok();
    }
    const char* names[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      std::vector<double> xs;
      std::string s = e.attr(names[k]);
      if (s.empty()) {
        (*out)[k] = 0.0f;
        continue;
      }
      GDVR_RETURN_IF_ERROR(parse_float_list(e, names[k], s, &xs));
      if (xs.size() != 1) return e.error(std::string("attribute '") + names[k] + "' must be one number");
      (*out)[k] = float(xs[0]);
    }
    return Status::Ok();
  }

  // ---- Shapes ----

  Expected<std::shared_ptr<const TriangleMesh>> load_mesh(const std::string& type, const std::string& path, int shape_index,
                                                         bool flip_tex_coords, const XmlElement& e) {
    std::string key = type + "|" + path + "|" + std::to_string(shape_index) + "|" + (flip_tex_coords ? "f" : "n");
    auto it = mesh_cache_.find(key);
    if (it != mesh_cache_.end()) return it->second;
    auto read = [&]() -> Expected<TriangleMesh> {
      if (type == "obj") {
        ObjOptions o;
        o.flip_tex_coords = flip_tex_coords;
        return read_obj(path, o);
      }
      if (type == "ply") return read_ply(path);
      return read_serialized(path, shape_index);
    };
    Expected<TriangleMesh> mesh = read();
    if (!mesh.ok()) return mesh.status().with_context(e.where() + ": ");
    MeshRepairReport report;
    GDVR_RETURN_IF_ERROR(validate_and_repair_mesh(&*mesh, path, &report).with_context(e.where() + ": "));
    if (report.changed()) scene_.warnings.push_back(e.where() + ": " + report.describe(path));
    if (mesh->triangle_count() == 0) return e.error("mesh '" + path + "' has no (non-degenerate) triangles");
    // Mitsuba smooths meshes whose file carries no normals.
    if (mesh->normals.empty()) compute_vertex_normals(&*mesh);
    auto shared = std::make_shared<const TriangleMesh>(std::move(*mesh));
    mesh_cache_[key] = shared;
    return shared;
  }

  Status build_shape(const XmlElement& e) {
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    std::string type = e.attr("type");
    Shape s;
    s.id = e.attr("id");
    GDVR_RETURN_IF_ERROR(props.get_transform("to_world", &s.to_world));
    GDVR_RETURN_IF_ERROR(props.get_bool("flip_normals", &s.flip_normals));
    if (one_of(type, {"obj", "ply", "serialized"})) {
      std::string filename;
      int shape_index = 0;
      bool flip_tex_coords = type == "obj";
      GDVR_RETURN_IF_ERROR(props.get_string("filename", &filename));
      GDVR_RETURN_IF_ERROR(props.get_bool("face_normals", &s.face_normals));
      if (type == "obj") GDVR_RETURN_IF_ERROR(props.get_bool("flip_tex_coords", &flip_tex_coords));
      if (type == "serialized") GDVR_RETURN_IF_ERROR(props.get_int("shape_index", &shape_index));
      if (filename.empty()) return props.error(e, "needs a 'filename'");
      Expected<std::string> path = resolve(filename, e);
      if (!path.ok()) return path.status();
      auto mesh = load_mesh(type, *path, shape_index, flip_tex_coords, e);
      if (!mesh.ok()) return mesh.status();
      s.mesh = *mesh;
    } else if (type == "rectangle") {
      s.mesh = shared_primitive("rectangle", [] { return make_rectangle_mesh(); });
    } else if (type == "cube") {
      s.mesh = shared_primitive("cube", [] { return make_cube_mesh(); });
    } else if (type == "disk") {
      s.mesh = shared_primitive("disk", [] { return make_disk_mesh(kDiskSegments); });
    } else if (type == "sphere") {
      s.type = ShapeType::kSphere;
      Vec3f center(0.0f);
      float radius = 1.0f;
      GDVR_RETURN_IF_ERROR(props.get_point("center", &center));
      GDVR_RETURN_IF_ERROR(props.get_float("radius", &radius));
      if (!(radius > 0)) return props.error(e, "radius must be positive");
      // As Mitsuba: to_world = to_world * translate(center) * scale(radius).
      s.to_world = s.to_world * Transform::translate(center) * Transform::scale(Vec3f(radius));
    } else {
      return unknown_plugin(e);
    }

    // ---- BSDF and area emitter: nested, referenced, or named ----
    std::vector<const XmlElement*> objects = props.take_unnamed();
    for (const char* n : {"bsdf", "emitter"})
      if (const XmlElement* c = props.take(n)) objects.push_back(c);
    const XmlElement* emitter_elem = nullptr;
    for (const XmlElement* c : objects) {
      Expected<const XmlElement*> t = deref(*c);
      if (!t.ok()) return t.status();
      const XmlElement& target = **t;
      if (target.tag == "bsdf") {
        if (s.bsdf >= 0) return props.error(*c, "more than one BSDF");
        Expected<int> idx = bsdf_index(*c);
        if (!idx.ok()) return idx.status();
        s.bsdf = *idx;
      } else if (target.tag == "emitter") {
        if (emitter_elem) return props.error(*c, "more than one emitter");
        if (target.attr("type") != "area") return props.error(*c, "only area emitters can be attached to a shape");
        emitter_elem = &target;
      } else {
        return props.error(*c, "unexpected <" + target.tag + "> inside a shape");
      }
    }
    GDVR_RETURN_IF_ERROR(props.check_all_used());
    if (s.bsdf < 0) s.bsdf = default_bsdf(/* emits = */ emitter_elem != nullptr);
    int shape_index = int(scene_.shapes.size());
    if (emitter_elem) {
      Emitter em;
      GDVR_RETURN_IF_ERROR(build_emitter(*emitter_elem, &em));
      em.shape = shape_index;
      em.to_world = s.to_world;
      scene_.emitters.push_back(em);
      s.emitter = int(scene_.emitters.size()) - 1;
      auto used = area_emitter_used_.find(em.id);
      if (used != area_emitter_used_.end()) used->second = true;
    }
    scene_.shapes.push_back(std::move(s));
    return Status::Ok();
  }

  template <typename Make>
  std::shared_ptr<const TriangleMesh> shared_primitive(const std::string& key, Make make) {
    auto it = mesh_cache_.find(key);
    if (it != mesh_cache_.end()) return it->second;
    auto m = std::make_shared<const TriangleMesh>(make());
    mesh_cache_[key] = m;
    return m;
  }

  // Mitsuba 3 gives a shape without a BSDF a diffuse one of reflectance 0.5,
  // or 0 where the shape emits (shape.cpp): a light reflects nothing unless
  // its file says so.
  int default_bsdf(bool emits) {
    int& index = emits ? default_emitter_bsdf_ : default_bsdf_;
    if (index < 0) {
      Bsdf b;
      b.type = BsdfType::kDiffuse;
      b.reflectance = Texture::constant(Rgb(emits ? 0.0f : 0.5f));
      b.finalize();
      scene_.bsdfs.push_back(b);
      index = int(scene_.bsdfs.size()) - 1;
    }
    return index;
  }

  // ---- Sensor, sampler, film, integrator ----

  Status build_sensor(const XmlElement& e) {
    if (e.attr("type") != "perspective") return unknown_plugin(e);
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    Camera& cam = scene_.camera;
    cam.id = e.attr("id");
    cam.fov_axis = FovAxis::kX;
    std::string fov_axis = "x";
    float focus_distance = 0;
    GDVR_RETURN_IF_ERROR(props.get_float("fov", &cam.fov));
    GDVR_RETURN_IF_ERROR(props.get_string("fov_axis", &fov_axis));
    GDVR_RETURN_IF_ERROR(props.get_float("near_clip", &cam.near_clip));
    GDVR_RETURN_IF_ERROR(props.get_float("far_clip", &cam.far_clip));
    // A pinhole camera has no focus; the parameter is accepted so that scenes
    // written for thin-lens previews still load.
    GDVR_RETURN_IF_ERROR(props.get_float("focus_distance", &focus_distance));
    GDVR_RETURN_IF_ERROR(props.get_transform("to_world", &cam.to_world));
    if (fov_axis == "x") cam.fov_axis = FovAxis::kX;
    else if (fov_axis == "y") cam.fov_axis = FovAxis::kY;
    else if (fov_axis == "diagonal") cam.fov_axis = FovAxis::kDiagonal;
    else if (fov_axis == "smaller") cam.fov_axis = FovAxis::kSmaller;
    else if (fov_axis == "larger") cam.fov_axis = FovAxis::kLarger;
    else return props.error(e, "fov_axis must be x, y, diagonal, smaller or larger, not '" + fov_axis + "'");
    if (!(cam.fov > 0 && cam.fov < 180)) return props.error(e, "fov must be in (0, 180) degrees");
    if (!(cam.near_clip > 0 && cam.far_clip > cam.near_clip)) return props.error(e, "need 0 < near_clip < far_clip");
    for (const XmlElement* c : props.take_unnamed()) {
      Expected<const XmlElement*> t = deref(*c);
      if (!t.ok()) return t.status();
      if ((*t)->tag == "sampler") {
        GDVR_RETURN_IF_ERROR(build_sampler(**t));
      } else if ((*t)->tag == "film") {
        GDVR_RETURN_IF_ERROR(build_film(**t));
      } else {
        return props.error(*c, "unexpected <" + (*t)->tag + "> inside a sensor");
      }
    }
    return props.check_all_used();
  }

  Status build_sampler(const XmlElement& e) {
    // gdvr draws every sample from its own hashed stream (core/math/rng.h);
    // only the sample count of Mitsuba's samplers carries over.
    std::string type = e.attr("type");
    bool legacy_type = e.from_legacy_file() && one_of(type, {"sobol", "halton", "hammersley"});
    if (!one_of(type, {"independent", "stratified", "multijitter", "ldsampler", "orthogonal"}) && !legacy_type)
      return unknown_plugin(e);
    if (legacy_type)
      scene_.warnings.push_back(e.where() + ": Mitsuba 0.x sampler '" + type + "' read for its sample_count only");
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    int seed = 0;
    bool jitter = true;
    GDVR_RETURN_IF_ERROR(props.get_int("sample_count", &scene_.defaults.spp));
    record_origin(props, "sample_count", &scene_.defaults.spp_origin);
    GDVR_RETURN_IF_ERROR(props.get_int("seed", &seed));
    GDVR_RETURN_IF_ERROR(props.get_bool("jitter", &jitter));
    if (e.from_legacy_file()) ignore_params(props, {"dimension", "scramble"}, "Mitsuba 0.x sample generation");
    if (scene_.defaults.spp <= 0) return props.error(e, "sample_count must be positive");
    return props.check_all_used();
  }

  Status build_film(const XmlElement& e) {
    // gdvr writes linear radiance (EXR) whatever the film: a Mitsuba 0.x
    // ldrfilm's tone mapping and gamma only changed the file it wrote.
    bool ldrfilm = e.from_legacy_file() && e.attr("type") == "ldrfilm";
    if (e.attr("type") != "hdrfilm" && !ldrfilm) return unknown_plugin(e);
    if (ldrfilm)
      scene_.warnings.push_back(e.where() + ": Mitsuba 0.x ldrfilm read as hdrfilm (gdvr writes linear EXR)");
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    // Mitsuba 3's hdrfilm accepts and ignores banner in any file.
    ignore_params(props, {"banner"}, "gdvr draws no banner");
    if (e.from_legacy_file())
      ignore_params(props, {"high_quality_edges", "attach_log", "gamma", "exposure", "tonemap_method", "key", "burn"},
                    "Mitsuba 0.x output settings; gdvr writes linear EXR");
    std::string pixel_format, file_format, component_format;
    bool sample_border = false;
    GDVR_RETURN_IF_ERROR(props.get_int("width", &scene_.defaults.width));
    GDVR_RETURN_IF_ERROR(props.get_int("height", &scene_.defaults.height));
    record_origin(props, "width", &scene_.defaults.width_origin);
    record_origin(props, "height", &scene_.defaults.height_origin);
    GDVR_RETURN_IF_ERROR(props.get_string("pixel_format", &pixel_format));
    GDVR_RETURN_IF_ERROR(props.get_string("file_format", &file_format));
    GDVR_RETURN_IF_ERROR(props.get_string("component_format", &component_format));
    GDVR_RETURN_IF_ERROR(props.get_bool("sample_border", &sample_border));
    if (scene_.defaults.width <= 0 || scene_.defaults.width > kMaxFilmResolution || scene_.defaults.height <= 0 ||
        scene_.defaults.height > kMaxFilmResolution)
      return props.error(e, "width and height must be in [1, " + std::to_string(kMaxFilmResolution) + "]");
    for (const XmlElement* c : props.take_unnamed()) {
      Expected<const XmlElement*> t = deref(*c);
      if (!t.ok()) return t.status();
      if ((*t)->tag != "rfilter") return props.error(*c, "unexpected <" + (*t)->tag + "> inside a film");
      GDVR_RETURN_IF_ERROR(build_rfilter(**t));
    }
    if (const XmlElement* r = props.take("rfilter")) GDVR_RETURN_IF_ERROR(build_rfilter(*r));
    return props.check_all_used();
  }

  Status build_rfilter(const XmlElement& e) {
    // Gradient-domain rendering needs pixels that do not share samples, so gdvr
    // always uses the box filter; other filters are accepted with a warning.
    std::string type = e.attr("type");
    if (!one_of(type, {"box", "tent", "gaussian", "mitchell", "catmullrom", "lanczos"})) return unknown_plugin(e);
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    float f;
    int i;
    for (const char* n : {"radius", "stddev", "B", "C"}) GDVR_RETURN_IF_ERROR(props.get_float(n, &f));
    GDVR_RETURN_IF_ERROR(props.get_int("lobes", &i));
    if (type != "box") scene_.warnings.push_back(e.where() + ": rfilter '" + type + "' replaced by box (gdvr renders box-filtered pixels)");
    return props.check_all_used();
  }

  Status build_integrator(const XmlElement& e) {
    std::string type = e.attr("type");
    if (type != "path")
      return Status(StatusCode::kUnimplemented,
                    e.where() + ": integrator '" + type + "' is not supported (gdvr reads only 'path'; choose pt/gpt/tgpt in the job)");
    MitsubaProps props;
    GDVR_RETURN_IF_ERROR(props.init(e));
    RenderDefaults& d = scene_.defaults;
    GDVR_RETURN_IF_ERROR(props.get_int("max_depth", &d.max_depth));
    GDVR_RETURN_IF_ERROR(props.get_int("rr_depth", &d.rr_depth));
    GDVR_RETURN_IF_ERROR(props.get_bool("hide_emitters", &d.hide_emitters));
    if (e.from_legacy_file())
      ignore_params(props, {"strict_normals"}, "Mitsuba 0.x only; gdvr follows Mitsuba 3, which has no strict normals");
    if (d.max_depth < -1) return props.error(e, "max_depth must be -1 (unbounded) or >= 0");
    if (d.rr_depth <= 0) return props.error(e, "rr_depth must be positive");
    return props.check_all_used();
  }

  // ---- Parameters without effect ----

  // Takes those of `names` that are present and records them in one warning:
  // settings that change nothing in gdvr's image (mostly what Mitsuba 0.x
  // films and samplers took and Mitsuba 3 dropped). Callers pass the 0.x ones
  // only for upgraded files: in a Mitsuba 3 file they stay unknown parameters.
  // Where parameter `name` (already read) was set, for RenderDefaults.
  static void record_origin(MitsubaProps& props, const std::string& name, SettingOrigin* origin) {
    const XmlElement* e = props.take(name);
    if (!e) return;
    origin->where = e->where();
    origin->params = e->params_used;
  }

  void ignore_params(MitsubaProps& props, std::initializer_list<const char*> names, const std::string& why) {
    std::string list;
    for (const char* n : names)
      if (props.take(n)) list += (list.empty() ? "'" : ", '") + std::string(n) + "'";
    if (!list.empty())
      scene_.warnings.push_back(props.plugin().where() + ": " + props.what() + ": ignored " + list + " (" + why + ")");
  }

  Status check_defaults() const {
    const RenderDefaults& d = scene_.defaults;
    if (d.width <= 0 || d.width > kMaxFilmResolution || d.height <= 0 || d.height > kMaxFilmResolution)
      return invalid_argument(scene_.source + ": film size out of range");
    if (d.spp <= 0) return invalid_argument(scene_.source + ": sample_count must be positive");
    return Status::Ok();
  }

  Expected<std::string> resolve(const std::string& filename, const XmlElement& e) const {
    return resolve_scene_file(filename, e, base_dir_, options_.asset_root);
  }

  Scene scene_;
  const XmlDocument& doc_;
  const LoadOptions& options_;
  std::string base_dir_;
  std::map<std::string, const XmlElement*> ids_;
  std::map<std::string, int> bsdf_cache_;
  std::map<std::string, Texture> texture_cache_;
  std::map<std::string, std::shared_ptr<const TriangleMesh>> mesh_cache_;
  std::map<std::string, bool> area_emitter_used_;
  int default_bsdf_ = -1;
  int default_emitter_bsdf_ = -1;
};

Expected<Scene> load_impl(const std::string& path, const std::string* text, const std::string& base_dir,
                          const LoadOptions& options) {
  XmlReadOptions xo;
  xo.params = options.params;
  xo.asset_root = options.asset_root;
  xo.base_dir = base_dir;
  XmlDocument doc;
  GDVR_RETURN_IF_ERROR(read_mitsuba_xml(path, text, xo, &doc));
  SceneBuilder builder(doc, options, base_dir);
  return builder.build();
}

}  // namespace

Expected<Scene> load_mitsuba_scene(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  // The root check comes first so that a request cannot probe for files outside it.
  if (!options.asset_root.empty() && !is_inside_root(path, options.asset_root))
    return invalid_argument(path + ": scene file is outside the asset root " + options.asset_root);
  if (!fs::is_regular_file(path, ec)) return Status(StatusCode::kNotFound, path + ": scene file not found");
  return load_impl(path, nullptr, fs::path(path).parent_path().string(), options);
}

Expected<Scene> load_mitsuba_scene_from_string(const std::string& xml, const std::string& base_dir,
                                               const LoadOptions& options) {
  return load_impl("<string>", &xml, base_dir, options);
}

}  // namespace gdvr
