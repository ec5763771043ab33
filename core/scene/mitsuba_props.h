// The parameters of one Mitsuba plugin element (<bsdf type=..>, <shape ..>):
// typed accessors that check the tag (<float>, <rgb>, ...), parse the value,
// and remember what was read, so that anything left unread is reported as an
// unknown parameter naming file, line, plugin and name.
#pragma once

#include <string>
#include <vector>

#include "core/math/transform.h"
#include "core/math/vec.h"
#include "core/scene/mitsuba_xml.h"
#include "core/scene/spectrum_to_rgb.h"
#include "core/util/status.h"

namespace gdvr {

// Tags that instantiate a plugin (as opposed to value tags like <float>).
bool is_plugin_tag(const std::string& tag);

class MitsubaProps {
 public:
  // Classifies the children of `plugin`; fails on malformed children
  // (unknown tags or attributes, missing names, duplicate names).
  Status init(const XmlElement& plugin);

  const XmlElement& plugin() const { return *plugin_; }
  // "bsdf 'diffuse'" for messages.
  std::string what() const;
  Status error(const XmlElement& at, const std::string& msg) const;

  bool has(const std::string& name) const;
  // The named child (any tag), marked as used; nullptr if absent.
  const XmlElement* take(const std::string& name);

  // Each getter leaves *out untouched when the parameter is absent.
  Status get_float(const std::string& name, float* out);
  Status get_int(const std::string& name, int* out);
  Status get_bool(const std::string& name, bool* out);
  Status get_string(const std::string& name, std::string* out);
  // The colour parameter `name` (<rgb>, <spectrum> or <float>), marked as
  // used; null when absent. The loader converts it (it may name a file).
  Expected<const XmlElement*> take_color(const std::string& name);
  Status get_point(const std::string& name, Vec3f* out);    // <point> or <vector>
  Status get_transform(const std::string& name, Transform* out);
  Status get_matrix(const std::string& name, Matrix4* out);  // unchecked (to_uv may be 2D)

  // Children without a name attribute that are plugins or refs, in order.
  std::vector<const XmlElement*> take_unnamed();

  // Error for the first child never read.
  Status check_all_used() const;

 private:
  struct Entry {
    const XmlElement* elem;
    mutable bool used;
  };
  const Entry* find(const std::string& name) const;
  Status expect_tag(const Entry& e, std::initializer_list<const char*> tags, const std::string& name) const;

  const XmlElement* plugin_ = nullptr;
  std::vector<Entry> named_;
  std::vector<Entry> unnamed_;
};

// Value parsing shared with the loader. All reject non-finite numbers.
Status parse_float_list(const XmlElement& at, const std::string& attr, const std::string& text, std::vector<double>* out);
// An <rgb>, <float> or inline <spectrum> value as linear sRGB, a spectrum
// converted for its role (spectrum_to_rgb.h). A <spectrum filename=...> is
// the loader's to read.
Status parse_rgb_value(const XmlElement& e, SpectrumRole role, Rgb* out);
Status parse_transform_element(const XmlElement& e, Matrix4* out);

}  // namespace gdvr
