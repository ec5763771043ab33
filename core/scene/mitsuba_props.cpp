#include "core/scene/mitsuba_props.h"

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace gdvr {

namespace {

const char* const kPluginTags[] = {"bsdf", "texture", "emitter", "shape", "sensor", "sampler", "film",
                                   "rfilter", "integrator", "medium", "phase", "volume"};

bool in_list(const std::string& s, std::initializer_list<const char*> list) {
  for (const char* x : list)
    if (s == x) return true;
  return false;
}

Status check_attrs(const XmlElement& e, std::initializer_list<const char*> allowed) {
  for (const auto& a : e.attrs)
    if (!in_list(a.first, allowed)) return e.error("unknown attribute '" + a.first + "' of <" + e.tag + ">");
  return Status::Ok();
}

Status require_attr(const XmlElement& e, const char* name, std::string* out) {
  const std::string* v = e.find_attr(name);
  if (!v) return e.error("<" + e.tag + "> needs attribute '" + name + "'");
  *out = *v;
  return Status::Ok();
}

Status parse_double(const XmlElement& at, const std::string& attr, const std::string& text, double* out) {
  std::vector<double> v;
  GDVR_RETURN_IF_ERROR(parse_float_list(at, attr, text, &v));
  if (v.size() != 1) return at.error("attribute '" + attr + "' must be one number, got '" + text + "'");
  *out = v[0];
  return Status::Ok();
}

Vec3f to_vec3(const double* v) { return Vec3f(float(v[0]), float(v[1]), float(v[2])); }

// x/y/z attributes (missing ones take `fallback`) or a 'value'/'alt' list of 3.
Status parse_xyz(const XmlElement& e, float fallback, const char* list_attr, Vec3f* out, bool* any) {
  *any = false;
  const std::string* list = e.find_attr(list_attr);
  if (list) {
    std::vector<double> v;
    GDVR_RETURN_IF_ERROR(parse_float_list(e, list_attr, *list, &v));
    if (v.size() != 3) return e.error("attribute '" + std::string(list_attr) + "' needs 3 numbers, got '" + *list + "'");
    if (e.find_attr("x") || e.find_attr("y") || e.find_attr("z"))
      return e.error("give either x/y/z or '" + std::string(list_attr) + "', not both");
    *out = to_vec3(v.data());
    *any = true;
    return Status::Ok();
  }
  const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    const std::string* s = e.find_attr(names[k]);
    double d = fallback;
    if (s) {
      GDVR_RETURN_IF_ERROR(parse_double(e, names[k], *s, &d));
      *any = true;
    }
    (*out)[k] = float(d);
  }
  return Status::Ok();
}

Status parse_vec3_attr(const XmlElement& e, const char* name, Vec3f* out) {
  std::string text;
  GDVR_RETURN_IF_ERROR(require_attr(e, name, &text));
  std::vector<double> v;
  GDVR_RETURN_IF_ERROR(parse_float_list(e, name, text, &v));
  if (v.size() != 3) return e.error("attribute '" + std::string(name) + "' needs 3 numbers, got '" + text + "'");
  *out = to_vec3(v.data());
  return Status::Ok();
}

}  // namespace

bool is_plugin_tag(const std::string& tag) {
  for (const char* t : kPluginTags)
    if (tag == t) return true;
  return false;
}

Status parse_float_list(const XmlElement& at, const std::string& attr, const std::string& text, std::vector<double>* out) {
  out->clear();
  const char* p = text.c_str();
  while (true) {
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r' || *p == ',') ++p;
    if (*p == '\0') break;
    char* end = nullptr;
    errno = 0;
    double d = std::strtod(p, &end);
    if (end == p || (*end != '\0' && *end != ' ' && *end != '\t' && *end != '\n' && *end != '\r' && *end != ','))
      return at.error("attribute '" + attr + "' of <" + at.tag + ">: '" + text + "' is not a number list");
    if (!std::isfinite(d) || errno == ERANGE)
      return at.error("attribute '" + attr + "' of <" + at.tag + ">: non-finite or out-of-range value in '" + text + "'");
    out->push_back(d);
    p = end;
  }
  if (out->empty()) return at.error("attribute '" + attr + "' of <" + at.tag + "> is empty");
  return Status::Ok();
}

Status parse_rgb_value(const XmlElement& e, SpectrumRole role, Rgb* out) {
  std::string text;
  GDVR_RETURN_IF_ERROR(require_attr(e, "value", &text));
  if (e.tag == "spectrum" && text.find(':') != std::string::npos) {
    // wavelength:value pairs, separated by commas and/or spaces.
    std::vector<double> wavelengths, values;
    std::string pairs = text;
    std::replace(pairs.begin(), pairs.end(), ',', ' ');
    std::istringstream in(pairs);
    std::string token;
    while (in >> token) {
      const size_t colon = token.find(':');
      char* end = nullptr;
      const double w = colon == std::string::npos ? NAN : std::strtod(token.c_str(), &end);
      const bool w_ok = colon != std::string::npos && end == token.c_str() + colon;
      const double v = w_ok ? std::strtod(token.c_str() + colon + 1, &end) : NAN;
      if (!w_ok || end != token.c_str() + token.size() || colon + 1 == token.size())
        return e.error("<spectrum> value: '" + token + "' is not a wavelength:value pair");
      wavelengths.push_back(w);
      values.push_back(v);
    }
    Expected<Rgb> rgb = spectrum_list_to_rgb(wavelengths, values, role);
    if (!rgb.ok()) return e.error(rgb.status().message());
    *out = *rgb;
    return Status::Ok();
  }
  std::vector<double> v;
  GDVR_RETURN_IF_ERROR(parse_float_list(e, "value", text, &v));
  if (v.size() == 1) {
    *out = e.tag == "spectrum" ? constant_spectrum_to_rgb(float(v[0]), role) : Rgb(float(v[0]));
  } else if (v.size() == 3 && e.tag != "spectrum" && e.tag != "float") {
    *out = Rgb(float(v[0]), float(v[1]), float(v[2]));
  } else {
    return e.error("<" + e.tag + "> value '" + text + "' must have " + (e.tag == "rgb" ? "1 or 3" : "1") + " component(s)");
  }
  return Status::Ok();
}

Status parse_transform_element(const XmlElement& e, Matrix4* out) {
  Matrix4 t = Matrix4::identity();
  for (const XmlElement& op : e.children) {
    Transform step;
    if (op.tag == "translate") {
      GDVR_RETURN_IF_ERROR(check_attrs(op, {"x", "y", "z", "value"}));
      Vec3f d;
      bool any;
      GDVR_RETURN_IF_ERROR(parse_xyz(op, 0.0f, "value", &d, &any));
      step = Transform::translate(d);
    } else if (op.tag == "rotate") {
      GDVR_RETURN_IF_ERROR(check_attrs(op, {"x", "y", "z", "axis", "value", "angle"}));
      Vec3f axis;
      bool any;
      const char* list = op.find_attr("axis") ? "axis" : "value";
      GDVR_RETURN_IF_ERROR(parse_xyz(op, 0.0f, list, &axis, &any));
      if (length_squared(axis) == 0.0f) return op.error("<rotate> needs a non-zero axis");
      std::string angle_text;
      GDVR_RETURN_IF_ERROR(require_attr(op, "angle", &angle_text));
      double angle;
      GDVR_RETURN_IF_ERROR(parse_double(op, "angle", angle_text, &angle));
      step = Transform::rotate(axis, float(angle));
    } else if (op.tag == "scale") {
      GDVR_RETURN_IF_ERROR(check_attrs(op, {"x", "y", "z", "value"}));
      Vec3f s(1.0f);
      const std::string* value = op.find_attr("value");
      if (value) {
        std::vector<double> v;
        GDVR_RETURN_IF_ERROR(parse_float_list(op, "value", *value, &v));
        if (op.find_attr("x") || op.find_attr("y") || op.find_attr("z"))
          return op.error("give either x/y/z or 'value', not both");
        if (v.size() == 1) s = Vec3f(float(v[0]));
        else if (v.size() == 3) s = to_vec3(v.data());
        else return op.error("<scale> value must have 1 or 3 numbers");
      } else {
        bool any;
        GDVR_RETURN_IF_ERROR(parse_xyz(op, 1.0f, "value", &s, &any));
      }
      if (s.x == 0.0f || s.y == 0.0f || s.z == 0.0f) return op.error("<scale> by zero makes the transform singular");
      step = Transform::scale(s);
    } else if (op.tag == "matrix") {
      GDVR_RETURN_IF_ERROR(check_attrs(op, {"value"}));
      std::string text;
      GDVR_RETURN_IF_ERROR(require_attr(op, "value", &text));
      std::vector<double> v;
      GDVR_RETURN_IF_ERROR(parse_float_list(op, "value", text, &v));
      Matrix4 m = Matrix4::identity();
      if (v.size() == 16) {
        for (int i = 0; i < 16; ++i) m.m[i / 4][i % 4] = v[i];
      } else if (v.size() == 9) {
        for (int i = 0; i < 9; ++i) m.m[i / 3][i % 3] = v[i];
      } else {
        return op.error("<matrix> needs 16 or 9 values, got " + std::to_string(v.size()));
      }
      if (!Transform::from_matrix(m, &step)) return op.error("<matrix> is singular or not finite");
    } else if (op.tag == "lookat") {
      GDVR_RETURN_IF_ERROR(check_attrs(op, {"origin", "target", "up"}));
      Vec3f origin, target, up(0, 1, 0);
      GDVR_RETURN_IF_ERROR(parse_vec3_attr(op, "origin", &origin));
      GDVR_RETURN_IF_ERROR(parse_vec3_attr(op, "target", &target));
      if (op.find_attr("up")) {
        GDVR_RETURN_IF_ERROR(parse_vec3_attr(op, "up", &up));
      } else {
        // Mitsuba picks any up vector orthogonal to the view direction.
        Vec3f d = normalize(target - origin);
        up = std::abs(d.y) < 0.9f ? Vec3f(0, 1, 0) : Vec3f(1, 0, 0);
      }
      if (!Transform::look_at(origin, target, up, &step))
        return op.error("<lookat> is degenerate (origin equals target, or up is parallel to the view direction)");
    } else {
      return op.error("unknown transform operation <" + op.tag + "> (expected translate, rotate, scale, matrix or lookat)");
    }
    if (!op.children.empty()) return op.error("<" + op.tag + "> must be empty");
    // Mitsuba applies each new element after the previous ones: T = new * T.
    t = step.matrix() * t;
  }
  Matrix4 inv;
  if (!t.is_finite() || !t.inverse(&inv)) return e.error("transform is singular or not finite");
  *out = t;
  return Status::Ok();
}

// ---- MitsubaProps ----

Status MitsubaProps::init(const XmlElement& plugin) {
  plugin_ = &plugin;
  for (const XmlElement& c : plugin.children) {
    const std::string* name = c.find_attr("name");
    if (is_plugin_tag(c.tag)) {
      GDVR_RETURN_IF_ERROR(check_attrs(c, {"type", "id", "name"}));
      if (!c.find_attr("type")) return c.error("<" + c.tag + "> needs a 'type'");
    } else if (c.tag == "ref") {
      GDVR_RETURN_IF_ERROR(check_attrs(c, {"id", "name"}));
      if (!c.find_attr("id")) return c.error("<ref> needs an 'id'");
      if (!c.children.empty()) return c.error("<ref> must be empty");
    } else if (in_list(c.tag, {"point", "vector"})) {
      GDVR_RETURN_IF_ERROR(check_attrs(c, {"name", "value", "x", "y", "z"}));
    } else if (c.tag == "transform") {
      GDVR_RETURN_IF_ERROR(check_attrs(c, {"name"}));
    } else if (in_list(c.tag, {"float", "integer", "boolean", "string", "rgb", "spectrum"})) {
      if (c.tag == "spectrum") {
        GDVR_RETURN_IF_ERROR(check_attrs(c, {"name", "value", "filename"}));
        if (!c.find_attr("value") == !c.find_attr("filename"))
          return c.error("<spectrum> needs either a 'value' or a 'filename'");
      } else {
        GDVR_RETURN_IF_ERROR(check_attrs(c, {"name", "value"}));
      }
    } else {
      return error(c, "unknown tag <" + c.tag + ">");
    }
    if (c.tag != "transform" && !is_plugin_tag(c.tag) && !c.children.empty()) return c.error("<" + c.tag + "> must be empty");
    bool is_value = !is_plugin_tag(c.tag) && c.tag != "ref";
    if (!name) {
      if (is_value) return c.error("<" + c.tag + "> needs a 'name'");
      unnamed_.push_back({&c, false});
      continue;
    }
    if (find(*name)) return error(c, "parameter '" + *name + "' given twice");
    named_.push_back({&c, false});
  }
  return Status::Ok();
}

std::string MitsubaProps::what() const { return plugin_->tag + " '" + plugin_->attr("type") + "'"; }

Status MitsubaProps::error(const XmlElement& at, const std::string& msg) const { return at.error(what() + ": " + msg); }

const MitsubaProps::Entry* MitsubaProps::find(const std::string& name) const {
  for (const Entry& e : named_)
    if (e.elem->attr("name") == name) return &e;
  return nullptr;
}

bool MitsubaProps::has(const std::string& name) const { return find(name) != nullptr; }

const XmlElement* MitsubaProps::take(const std::string& name) {
  const Entry* e = find(name);
  if (!e) return nullptr;
  e->used = true;
  return e->elem;
}

Status MitsubaProps::expect_tag(const Entry& e, std::initializer_list<const char*> tags, const std::string& name) const {
  if (in_list(e.elem->tag, tags)) return Status::Ok();
  std::string expected;
  for (const char* t : tags) expected += std::string(expected.empty() ? "" : " or ") + "<" + t + ">";
  return error(*e.elem, "parameter '" + name + "' must be " + expected + ", not <" + e.elem->tag + ">");
}

Status MitsubaProps::get_float(const std::string& name, float* out) {
  const Entry* e = find(name);
  if (!e) return Status::Ok();
  e->used = true;
  GDVR_RETURN_IF_ERROR(expect_tag(*e, {"float", "integer"}, name));
  double d;
  GDVR_RETURN_IF_ERROR(parse_double(*e->elem, "value", e->elem->attr("value"), &d));
  *out = float(d);
  return Status::Ok();
}

Status MitsubaProps::get_int(const std::string& name, int* out) {
  const Entry* e = find(name);
  if (!e) return Status::Ok();
  e->used = true;
  GDVR_RETURN_IF_ERROR(expect_tag(*e, {"integer"}, name));
  std::string text = e->elem->attr("value");
  const char* p = text.c_str();
  while (*p == ' ') ++p;
  char* end = nullptr;
  errno = 0;
  long v = std::strtol(p, &end, 10);
  while (end && *end == ' ') ++end;
  if (end == p || *end != '\0' || errno == ERANGE || v < INT_MIN || v > INT_MAX)
    return error(*e->elem, "parameter '" + name + "': '" + text + "' is not an integer");
  *out = int(v);
  return Status::Ok();
}

Status MitsubaProps::get_bool(const std::string& name, bool* out) {
  const Entry* e = find(name);
  if (!e) return Status::Ok();
  e->used = true;
  GDVR_RETURN_IF_ERROR(expect_tag(*e, {"boolean"}, name));
  std::string text = e->elem->attr("value");
  if (text == "true" || text == "1") *out = true;
  else if (text == "false" || text == "0") *out = false;
  else return error(*e->elem, "parameter '" + name + "': '" + text + "' is not a boolean (true or false)");
  return Status::Ok();
}

Status MitsubaProps::get_string(const std::string& name, std::string* out) {
  const Entry* e = find(name);
  if (!e) return Status::Ok();
  e->used = true;
  GDVR_RETURN_IF_ERROR(expect_tag(*e, {"string"}, name));
  const std::string* v = e->elem->find_attr("value");
  if (!v) return e->elem->error("<string> needs attribute 'value'");
  *out = *v;
  return Status::Ok();
}

Expected<const XmlElement*> MitsubaProps::take_color(const std::string& name) {
  const Entry* e = find(name);
  if (!e) return static_cast<const XmlElement*>(nullptr);
  e->used = true;
  GDVR_RETURN_IF_ERROR(expect_tag(*e, {"rgb", "spectrum", "float"}, name));
  return e->elem;
}

Status MitsubaProps::get_point(const std::string& name, Vec3f* out) {
  const Entry* e = find(name);
  if (!e) return Status::Ok();
  e->used = true;
  GDVR_RETURN_IF_ERROR(expect_tag(*e, {"point", "vector"}, name));
  bool any = false;
  Vec3f v;
  GDVR_RETURN_IF_ERROR(parse_xyz(*e->elem, 0.0f, "value", &v, &any));
  if (!any) return error(*e->elem, "parameter '" + name + "' needs x/y/z or a value");
  *out = v;
  return Status::Ok();
}

Status MitsubaProps::get_matrix(const std::string& name, Matrix4* out) {
  const Entry* e = find(name);
  if (!e) return Status::Ok();
  e->used = true;
  GDVR_RETURN_IF_ERROR(expect_tag(*e, {"transform"}, name));
  return parse_transform_element(*e->elem, out);
}

Status MitsubaProps::get_transform(const std::string& name, Transform* out) {
  Matrix4 m;
  if (!has(name)) return Status::Ok();
  GDVR_RETURN_IF_ERROR(get_matrix(name, &m));
  if (!Transform::from_matrix(m, out)) return error(*find(name)->elem, "transform '" + name + "' is singular or not finite");
  return Status::Ok();
}

std::vector<const XmlElement*> MitsubaProps::take_unnamed() {
  std::vector<const XmlElement*> out;
  for (const Entry& e : unnamed_) {
    e.used = true;
    out.push_back(e.elem);
  }
  return out;
}

Status MitsubaProps::check_all_used() const {
  for (const Entry& e : named_)
    if (!e.used) return error(*e.elem, "unknown parameter '" + e.elem->attr("name") + "'");
  for (const Entry& e : unnamed_)
    if (!e.used) return error(*e.elem, "unexpected nested <" + e.elem->tag + ">");
  return Status::Ok();
}

}  // namespace gdvr
