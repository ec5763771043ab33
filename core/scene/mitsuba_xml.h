// First stage of Mitsuba scene loading: reads the XML (pugixml), expands
// <include>, applies <default> and $name substitution, upgrades the elements
// of Mitsuba 0.x files as Mitsuba 3 does (mitsuba_upgrade.h), and yields a
// plain element tree in which every element knows its file and line. The
// second stage (mitsuba_loader.cpp) turns this tree into a Scene.
#pragma once

#include <deque>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/util/status.h"

namespace gdvr {

struct XmlSource {
  std::string path;  // as shown in messages
  std::string dir;   // folder of the file, for relative references
  // <scene version> below 2.0.0: a Mitsuba 0.x file, upgraded to Mitsuba 3
  // names as it was read (mitsuba_upgrade.h).
  bool legacy = false;
};

struct XmlElement {
  std::string tag;
  std::vector<std::pair<std::string, std::string>> attrs;  // after $name substitution
  // The $name parameters substituted into attrs, in order: where a value came
  // from when a limit refuses it (e.g. a film width of "$res").
  std::vector<std::string> params_used;
  std::vector<XmlElement> children;
  const XmlSource* source = nullptr;
  int line = 0;

  const std::string* find_attr(const std::string& name) const {
    for (const auto& a : attrs)
      if (a.first == name) return &a.second;
    return nullptr;
  }
  std::string attr(const std::string& name) const {
    const std::string* v = find_attr(name);
    return v ? *v : std::string();
  }
  // Read from a Mitsuba 0.x file (see XmlSource::legacy).
  bool from_legacy_file() const { return source && source->legacy; }
  // "file.xml:12"
  std::string where() const;
  // invalid_argument("file.xml:12: <msg>")
  Status error(const std::string& msg) const;
};

// Owns the sources (so that XmlElement::source stays valid) and the tree.
struct XmlDocument {
  std::deque<XmlSource> sources;
  XmlElement root;  // the <scene> element, includes expanded
  std::map<std::string, std::string> params;  // final parameter values
  std::vector<std::string> warnings;          // for Scene::warnings (upgraded files, renamed ids)
};

struct XmlReadOptions {
  std::map<std::string, std::string> params;  // override <default>
  std::string asset_root;                     // empty: no restriction
  std::string base_dir;                       // the main scene's folder
};

// Reads `path` (or, with `text` non-null, that text named `path`).
Status read_mitsuba_xml(const std::string& path, const std::string* text, const XmlReadOptions& options,
                        XmlDocument* doc);

// Resolves `filename` referenced from `where`: relative names are tried next
// to the referencing file, then in the main scene's folder. Enforces the asset
// root (INVALID_ARGUMENT naming the path) and existence (NOT_FOUND).
Expected<std::string> resolve_scene_file(const std::string& filename, const XmlElement& where, const std::string& base_dir,
                                         const std::string& asset_root);

}  // namespace gdvr
