#include "core/scene/mitsuba_upgrade.h"

#include "core/scene/mitsuba_props.h"

namespace gdvr {

namespace {

// ASCII only, as Mitsuba's std::islower/isupper in the "C" locale.
bool is_lower(char c) { return c >= 'a' && c <= 'z'; }
bool is_upper(char c) { return c >= 'A' && c <= 'Z'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

// ---- Per-element rules: names, tags, ids ----

void upgrade_names(XmlElement* e, std::vector<std::string>* warnings) {
  if (e->tag == "lookAt") e->tag = "lookat";
  for (auto& [key, value] : e->attrs) {
    if (key == "name" && e->tag != "default") {
      value = camel_to_snake_case(value);
    } else if (key == "id" && !value.empty() && value[0] == '_') {
      // Mitsuba 3 reserves ids starting with '_' for the objects it names
      // itself; refs are renamed alike, so references still resolve.
      std::string renamed = "ID" + value + "__UPGR";
      if (e->tag != "ref")
        warnings->push_back(e->where() + ": id '" + value + "' renamed to '" + renamed +
                            "' (ids starting with '_' are reserved in Mitsuba 3)");
      value = renamed;
    }
  }
}

// ---- Per-plugin rules: parameters that changed ----

void upgrade_diffuse(XmlElement* e) {
  if (e->tag != "bsdf" || e->attr("type") != "diffuse") return;
  for (XmlElement& c : e->children)
    for (auto& [key, value] : c.attrs)
      if (key == "name" && value == "diffuse_reflectance") value = "reflectance";
}

// Mitsuba 0.x textures took uoffset/voffset/uscale/vscale; Mitsuba 3 takes a
// to_uv transform. uv' = scale * (uv + offset), as Mitsuba 3's upgrade builds it.
Status fold_uv_floats(XmlElement* e) {
  struct Part {
    const char* name;
    std::string value = {};
    bool present = false;
  };
  Part parts[4] = {{"uoffset"}, {"voffset"}, {"uscale"}, {"vscale"}};
  auto part_of = [&](const XmlElement& c) -> Part* {
    if (c.tag != "float" && c.tag != "integer") return nullptr;
    for (Part& p : parts)
      if (c.attr("name") == p.name) return &p;
    return nullptr;
  };
  bool any = false;
  for (const XmlElement& c : e->children) any = any || part_of(c);
  if (!any) return Status::Ok();

  const XmlElement* first = nullptr;  // messages about to_uv name the first of the floats
  std::vector<XmlElement> kept;
  for (XmlElement& c : e->children) {
    Part* part = part_of(c);
    if (!part) {
      kept.push_back(std::move(c));
      continue;
    }
    if (part->present) return c.error("parameter '" + std::string(part->name) + "' given twice");
    std::vector<double> v;
    GDVR_RETURN_IF_ERROR(parse_float_list(c, "value", c.attr("value"), &v));
    if (v.size() != 1) return c.error("'" + std::string(part->name) + "' must be one number");
    part->value = c.attr("value");
    part->present = true;
    if (!first) first = &c;
  }
  const XmlSource* source = first->source;
  const int line = first->line;

  XmlElement to_uv;
  to_uv.tag = "transform";
  to_uv.attrs.emplace_back("name", "to_uv");
  to_uv.source = source;
  to_uv.line = line;
  auto op = [&](const char* tag, const Part& u, const Part& v) {
    if (!u.present && !v.present) return;
    XmlElement o;
    o.tag = tag;
    o.source = source;
    o.line = line;
    // A missing coordinate takes the operation's neutral value (0 or 1).
    if (u.present) o.attrs.emplace_back("x", u.value);
    if (v.present) o.attrs.emplace_back("y", v.value);
    to_uv.children.push_back(std::move(o));
  };
  // Transform elements apply in order: first the offset, then the scale.
  op("translate", parts[0], parts[1]);
  op("scale", parts[2], parts[3]);
  kept.push_back(std::move(to_uv));
  e->children = std::move(kept);
  return Status::Ok();
}

}  // namespace

bool parse_scene_version(const std::string& text, SceneVersion* out) {
  unsigned parts[3];
  int count = 0;
  size_t i = 0;
  while (i < text.size()) {
    if (text[i] == '.' || text[i] == ' ') {
      ++i;
      continue;
    }
    if (count == 3 || !is_digit(text[i])) return false;
    // Like Mitsuba's std::stoul: the leading digits count, a suffix such as
    // "-dev" is skipped.
    unsigned long n = 0;
    for (; i < text.size() && is_digit(text[i]); ++i) {
      n = n * 10 + unsigned(text[i] - '0');
      if (n > 1000000) return false;
    }
    while (i < text.size() && text[i] != '.' && text[i] != ' ') ++i;
    parts[count++] = unsigned(n);
  }
  if (count != 3) return false;
  out->major = parts[0];
  out->minor = parts[1];
  out->patch = parts[2];
  return true;
}

std::string camel_to_snake_case(const std::string& name) {
  std::string out;
  out.reserve(name.size() + 4);
  for (size_t i = 0; i < name.size(); ++i) {
    if (i > 0 && is_lower(name[i - 1]) && is_upper(name[i])) {
      // The whole run of capitals is one word: intIOR -> int_ior.
      out += '_';
      for (; i < name.size() && is_upper(name[i]); ++i) out += char(name[i] - 'A' + 'a');
      --i;
      continue;
    }
    out += name[i];
  }
  return out;
}

Status upgrade_legacy_elements(XmlElement* root, std::vector<std::string>* warnings) {
  const bool legacy = root->source && root->source->legacy;
  if (legacy) upgrade_names(root, warnings);
  for (XmlElement& c : root->children) GDVR_RETURN_IF_ERROR(upgrade_legacy_elements(&c, warnings));
  // After the children, whose names are snake_case by now.
  if (legacy) {
    upgrade_diffuse(root);
    GDVR_RETURN_IF_ERROR(fold_uv_floats(root));
  }
  return Status::Ok();
}

}  // namespace gdvr
