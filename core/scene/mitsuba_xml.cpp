#include "core/scene/mitsuba_xml.h"

#include <pugixml.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/scene/mitsuba_upgrade.h"
#include "core/util/path_confinement.h"

namespace gdvr {

namespace fs = std::filesystem;

std::string XmlElement::where() const {
  return (source ? source->path : std::string("<unknown>")) + ":" + std::to_string(line);
}

Status XmlElement::error(const std::string& msg) const { return invalid_argument(where() + ": " + msg); }

namespace {

constexpr int kMaxIncludeDepth = 32;

// Line starts of a buffer, for turning pugixml byte offsets into line numbers.
class LineIndex {
 public:
  explicit LineIndex(const std::string& text) {
    starts_.push_back(0);
    for (size_t i = 0; i < text.size(); ++i)
      if (text[i] == '\n') starts_.push_back(i + 1);
  }
  int line_of(ptrdiff_t offset) const {
    if (offset < 0) return 0;
    auto it = std::upper_bound(starts_.begin(), starts_.end(), size_t(offset));
    return int(it - starts_.begin());
  }

 private:
  std::vector<size_t> starts_;
};

class XmlReader {
 public:
  XmlReader(const XmlReadOptions& options, XmlDocument* doc) : options_(options), doc_(doc) {
    doc_->params = options.params;
  }

  Status read_root(const std::string& path, const std::string* text) {
    std::string content;
    if (text) {
      content = *text;
    } else {
      GDVR_RETURN_IF_ERROR(read_file(path, &content));
    }
    stack_.push_back(canonical_or_self(path));
    XmlElement* root = &doc_->root;
    GDVR_RETURN_IF_ERROR(parse(path, content, /*include_site=*/nullptr, root));
    // One pass over the whole tree: each element is upgraded by the version of
    // the file it came from, so that 0.x and 3.x files can include each other.
    bool any_legacy =
        std::any_of(doc_->sources.begin(), doc_->sources.end(), [](const XmlSource& s) { return s.legacy; });
    return any_legacy ? upgrade_legacy_elements(root, &doc_->warnings) : Status::Ok();
  }

 private:
  static std::string canonical_or_self(const std::string& path) {
    std::error_code ec;
    fs::path c = fs::weakly_canonical(path, ec);
    return ec ? path : c.string();
  }

  Status read_file(const std::string& path, std::string* out) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return not_found(path + ": cannot open scene file");
    std::ostringstream ss;
    ss << in.rdbuf();
    *out = ss.str();
    return Status::Ok();
  }

  // Parses one file. For the main file, `out` receives the <scene> element; for
  // an include, the included <scene>'s children are appended to `out`.
  Status parse(const std::string& path, const std::string& content, const XmlElement* include_site, XmlElement* out) {
    doc_->sources.push_back(XmlSource{path, fs::path(path).parent_path().string()});
    XmlSource* src = &doc_->sources.back();
    LineIndex lines(content);
    pugi::xml_document xml;
    pugi::xml_parse_result res = xml.load_buffer(content.data(), content.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!res)
      return invalid_argument(path + ":" + std::to_string(lines.line_of(res.offset)) + ": XML parse error: " +
                              res.description());
    pugi::xml_node scene;
    for (pugi::xml_node n = xml.first_child(); n; n = n.next_sibling()) {
      if (n.type() != pugi::node_element) continue;
      if (scene) return invalid_argument(path + ":" + std::to_string(lines.line_of(n.offset_debug())) + ": more than one root element");
      scene = n;
    }
    if (!scene) return invalid_argument(path + ":1: no root element");
    int scene_line = lines.line_of(scene.offset_debug());
    if (std::string(scene.name()) != "scene")
      return invalid_argument(path + ":" + std::to_string(scene_line) + ": root element must be <scene>, not <" +
                              scene.name() + ">");
    for (pugi::xml_attribute a = scene.first_attribute(); a; a = a.next_attribute())
      if (std::string(a.name()) != "version")
        return invalid_argument(path + ":" + std::to_string(scene_line) + ": unknown attribute '" + a.name() + "' of <scene>");
    // Without a version a file is read as Mitsuba 3 (Mitsuba itself requires one).
    if (pugi::xml_attribute v = scene.attribute("version")) {
      SceneVersion version;
      if (!parse_scene_version(v.value(), &version))
        return invalid_argument(path + ":" + std::to_string(scene_line) + ": invalid version number '" + v.value() +
                                "' of <scene> (expected major.minor.patch, e.g. 3.0.0)");
      src->legacy = version.is_legacy();
      if (src->legacy)
        doc_->warnings.push_back(path + ":" + std::to_string(scene_line) + ": Mitsuba " + v.value() +
                                 " file upgraded to Mitsuba 3 names as Mitsuba 3 does (maxDepth -> max_depth, ...)");
    }
    if (!include_site) {
      out->tag = "scene";
      out->source = src;
      out->line = scene_line;
    }
    return convert_children(scene, *src, lines, out);
  }

  Status convert_children(pugi::xml_node node, const XmlSource& src, const LineIndex& lines, XmlElement* out) {
    for (pugi::xml_node c = node.first_child(); c; c = c.next_sibling()) {
      int line = lines.line_of(c.offset_debug());
      if (c.type() == pugi::node_pcdata || c.type() == pugi::node_cdata) {
        std::string t = c.value();
        if (std::all_of(t.begin(), t.end(), [](unsigned char ch) { return std::isspace(ch); })) continue;
        return invalid_argument(src.path + ":" + std::to_string(line) + ": unexpected text inside <" + node.name() + ">");
      }
      if (c.type() != pugi::node_element) continue;
      XmlElement e;
      e.tag = c.name();
      e.source = &src;
      e.line = line;
      for (pugi::xml_attribute a = c.first_attribute(); a; a = a.next_attribute()) {
        std::string value = a.value();
        // <default> values are taken literally, as Mitsuba does.
        if (e.tag != "default") GDVR_RETURN_IF_ERROR(substitute(&value, &e));
        e.attrs.emplace_back(a.name(), value);
      }
      if (e.tag == "default") {
        GDVR_RETURN_IF_ERROR(handle_default(c, e));
        continue;
      }
      if (e.tag == "include") {
        GDVR_RETURN_IF_ERROR(handle_include(c, e, out));
        continue;
      }
      GDVR_RETURN_IF_ERROR(convert_children(c, src, lines, &e));
      out->children.push_back(std::move(e));
    }
    return Status::Ok();
  }

  // Replaces every $name by its parameter value. A '$' not followed by a name
  // character is kept (Mitsuba does the same).
  Status substitute(std::string* value, XmlElement* e) {
    if (value->find('$') == std::string::npos) return Status::Ok();
    std::string out;
    for (size_t i = 0; i < value->size();) {
      char ch = (*value)[i];
      if (ch != '$') {
        out += ch;
        ++i;
        continue;
      }
      size_t j = i + 1;
      while (j < value->size() && (std::isalnum(static_cast<unsigned char>((*value)[j])) || (*value)[j] == '_')) ++j;
      if (j == i + 1) {
        out += ch;
        ++i;
        continue;
      }
      std::string name = value->substr(i + 1, j - i - 1);
      auto it = doc_->params.find(name);
      if (it == doc_->params.end())
        return e->error("undefined parameter '$" + name + "' (no <default> and not set with a parameter override)");
      out += it->second;
      e->params_used.push_back(name);
      i = j;
    }
    *value = out;
    return Status::Ok();
  }

  Status handle_default(pugi::xml_node node, const XmlElement& e) {
    if (node.first_child()) return e.error("<default> must be empty");
    const std::string* name = e.find_attr("name");
    const std::string* value = e.find_attr("value");
    for (const auto& a : e.attrs)
      if (a.first != "name" && a.first != "value") return e.error("unknown attribute '" + a.first + "' of <default>");
    if (!name || !value || name->empty()) return e.error("<default> needs 'name' and 'value'");
    doc_->params.emplace(*name, *value);  // an override or an earlier default wins
    return Status::Ok();
  }

  Status handle_include(pugi::xml_node node, const XmlElement& e, XmlElement* out) {
    if (node.first_child()) return e.error("<include> must be empty");
    for (const auto& a : e.attrs)
      if (a.first != "filename") return e.error("unknown attribute '" + a.first + "' of <include>");
    const std::string* filename = e.find_attr("filename");
    if (!filename || filename->empty()) return e.error("<include> needs 'filename'");
    if (stack_.size() >= size_t(kMaxIncludeDepth)) return e.error("includes nested deeper than 32 levels");
    Expected<std::string> path = resolve_scene_file(*filename, e, options_.base_dir, options_.asset_root);
    if (!path.ok()) return path.status();
    std::string canon = canonical_or_self(*path);
    if (std::find(stack_.begin(), stack_.end(), canon) != stack_.end()) {
      std::string chain;
      for (const auto& s : stack_) chain += s + " -> ";
      return e.error("include cycle: " + chain + canon);
    }
    std::string content;
    GDVR_RETURN_IF_ERROR(read_file(*path, &content));
    stack_.push_back(canon);
    Status st = parse(*path, content, &e, out);
    stack_.pop_back();
    return st;
  }

  const XmlReadOptions& options_;
  XmlDocument* doc_;
  std::vector<std::string> stack_;  // canonical paths of the files being read, for cycle detection
};

}  // namespace

Status read_mitsuba_xml(const std::string& path, const std::string* text, const XmlReadOptions& options,
                        XmlDocument* doc) {
  XmlReader reader(options, doc);
  return reader.read_root(path, text);
}

Expected<std::string> resolve_scene_file(const std::string& filename, const XmlElement& where, const std::string& base_dir,
                                         const std::string& asset_root) {
  if (filename.empty()) return where.error("empty file name");
  std::vector<fs::path> candidates;
  fs::path f(filename);
  if (f.is_absolute()) {
    candidates.push_back(f);
  } else {
    if (where.source && !where.source->dir.empty()) candidates.push_back(fs::path(where.source->dir) / f);
    candidates.push_back(fs::path(base_dir.empty() ? "." : base_dir) / f);
  }
  fs::path root;
  if (!asset_root.empty()) {
    std::error_code ec;
    root = fs::weakly_canonical(asset_root, ec);
    if (ec) return invalid_argument("asset root '" + asset_root + "' cannot be resolved: " + ec.message());
  }
  for (const fs::path& c : candidates) {
    std::error_code ec;
    fs::path canon = fs::weakly_canonical(c, ec);
    if (ec) canon = c.lexically_normal();
    // Check the root before existence, so that a scene cannot probe for files outside it.
    if (!root.empty() && !is_inside_root(canon, root))
      return invalid_argument(where.where() + ": '" + filename + "' resolves to " + canon.string() +
                              ", outside the asset root " + root.string());
    if (fs::is_regular_file(canon, ec)) return c.lexically_normal().string();
  }
  std::string looked;
  for (const fs::path& c : candidates) looked += (looked.empty() ? "" : ", ") + c.lexically_normal().string();
  return Status(StatusCode::kNotFound, where.where() + ": file '" + filename + "' not found (looked for " + looked + ")");
}

}  // namespace gdvr
