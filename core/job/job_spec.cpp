// JobSpec <-> JSON and the render-farm frame range syntax.
//
// The JSON schema is the protobuf JSON form of gdvr.v1.JobSpec with the proto
// field names. Keyframes also accept the hand-written conveniences `frame`
// (converted with the job's fps) and translate/rotate/scale; tracks may sit
// under "animation" (as the proto has them) or directly at the top level.
#include "core/job/job_spec.h"

#include <nlohmann/json.hpp>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>

#include "core/job/job_validation.h"
#include "core/util/echo_text.h"

namespace gdvr {

using nlohmann::json;

namespace {

// Even without a caller limit, a range must not allocate without bound.
constexpr size_t kHardFrameLimit = 1000000;

std::string trim(const std::string& s) {
  size_t b = 0, e = s.size();
  while (b < e && std::isspace(static_cast<unsigned char>(s[b]))) ++b;
  while (e > b && std::isspace(static_cast<unsigned char>(s[e - 1]))) --e;
  return s.substr(b, e - b);
}

// A non-negative decimal integer (digits only, no sign). Values above
// INT_MAX come back as INT_MAX + 1 so that callers can say "too large"
// rather than "not a number".
bool parse_uint(const std::string& s, long long* out) {
  if (s.empty()) return false;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  size_t first = s.find_first_not_of('0');
  if (first == std::string::npos) first = s.size();
  if (s.size() - first > 10) {
    *out = (long long)std::numeric_limits<int>::max() + 1;
    return true;
  }
  *out = std::min(std::atoll(s.c_str()), (long long)std::numeric_limits<int>::max() + 1);
  return true;
}

// ---- JSON field readers: each names the JSON path in its errors ----

class JsonReader {
 public:
  explicit JsonReader(std::string origin) : origin_(std::move(origin)) {}

  // Paths hold the client's JSON keys, so they are echoed bounded.
  Status error(const std::string& path, const std::string& msg) const {
    return invalid_argument(origin_ + ": " + echo_text(path) + ": " + msg);
  }

  Status check_object(const json& j, const std::string& path, std::initializer_list<const char*> allowed) const {
    if (!j.is_object()) return error(path, "must be an object");
    for (auto it = j.begin(); it != j.end(); ++it) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || it.key() == a;
      if (!ok) return error(path + "." + echo_text(it.key()), "unknown field");
    }
    return Status::Ok();
  }

  Status get(const json& j, const std::string& path, std::string* out) const {
    if (!j.is_string()) return error(path, "must be a string");
    *out = j.get<std::string>();
    return Status::Ok();
  }
  Status get(const json& j, const std::string& path, double* out) const {
    if (!j.is_number()) return error(path, "must be a number");
    double v = j.get<double>();
    if (!std::isfinite(v)) return error(path, "must be finite");
    *out = v;
    return Status::Ok();
  }
  Status get(const json& j, const std::string& path, int* out) const {
    if (j.is_number_integer()) {
      long long v = j.get<long long>();
      if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) return error(path, "out of range");
      *out = int(v);
      return Status::Ok();
    }
    if (j.is_number_float()) {
      double v = j.get<double>();
      if (v == std::floor(v) && std::abs(v) < 2e9) {
        *out = int(v);
        return Status::Ok();
      }
    }
    return error(path, "must be an integer");
  }
  Status get(const json& j, const std::string& path, bool* out) const {
    if (!j.is_boolean()) return error(path, "must be true or false");
    *out = j.get<bool>();
    return Status::Ok();
  }
  // Protobuf's JSON form writes 64-bit integers as strings; accept both.
  Status get(const json& j, const std::string& path, uint64_t* out) const {
    if (j.is_number_unsigned()) {
      *out = j.get<uint64_t>();
      return Status::Ok();
    }
    if (j.is_string()) {
      std::string s = j.get<std::string>();
      bool digits = !s.empty() && s.size() <= 20;
      for (char c : s) digits = digits && std::isdigit(static_cast<unsigned char>(c));
      errno = 0;
      unsigned long long v = digits ? std::strtoull(s.c_str(), nullptr, 10) : 0;
      if (digits && errno != ERANGE) {
        *out = v;
        return Status::Ok();
      }
    }
    return error(path, "must be a non-negative 64-bit integer (number or decimal string)");
  }
  Status get_vec(const json& j, const std::string& path, size_t n, std::vector<double>* out) const {
    if (!j.is_array() || j.size() != n) return error(path, "must be an array of " + std::to_string(n) + " numbers");
    out->resize(n);
    for (size_t i = 0; i < n; ++i) GDVR_RETURN_IF_ERROR(get(j[i], path + "[" + std::to_string(i) + "]", &(*out)[i]));
    return Status::Ok();
  }

  // A name from the enum's table; the error lists the table's names.
  template <typename Enum, size_t N>
  Status get_name(const json& j, const std::string& path, const EnumNames<Enum, N>& names, Enum* out) const {
    std::string name;
    GDVR_RETURN_IF_ERROR(get(j, path, &name));
    std::optional<Enum> v = enum_from_name(names, name);
    if (!v) return error(path, "must be " + enum_name_list(names) + ", not '" + echo_text(name) + "'");
    *out = *v;
    return Status::Ok();
  }

  template <typename T>
  Status opt(const json& obj, const char* key, const std::string& path, T* out) const {
    auto it = obj.find(key);
    if (it == obj.end() || it->is_null()) return Status::Ok();
    return get(*it, path + "." + key, out);
  }
  Status opt(const json& obj, const char* key, const std::string& path, std::optional<int>* out) const {
    auto it = obj.find(key);
    if (it == obj.end() || it->is_null()) return Status::Ok();
    int v = 0;
    GDVR_RETURN_IF_ERROR(get(*it, path + "." + key, &v));
    *out = v;
    return Status::Ok();
  }
  template <typename Enum, size_t N>
  Status opt_name(const json& obj, const char* key, const std::string& path, const EnumNames<Enum, N>& names,
                  Enum* out) const {
    auto it = obj.find(key);
    if (it == obj.end() || it->is_null()) return Status::Ok();
    return get_name(*it, path + "." + key, names, out);
  }

 private:
  std::string origin_;
};

Vec3f to_vec3f(const std::vector<double>& v) { return Vec3f(float(v[0]), float(v[1]), float(v[2])); }

Status parse_keyframe(const JsonReader& r, const json& j, const std::string& path, double fps, Keyframe* key) {
  GDVR_RETURN_IF_ERROR(r.check_object(j, path, {"time", "frame", "matrix", "lookat", "translate", "rotate", "scale"}));
  bool has_time = j.contains("time"), has_frame = j.contains("frame");
  if (has_time && has_frame) return r.error(path, "give either 'time' or 'frame', not both");
  key->time = 0;
  GDVR_RETURN_IF_ERROR(r.opt(j, "time", path, &key->time));
  if (has_frame) {
    double frame = 0;
    GDVR_RETURN_IF_ERROR(r.opt(j, "frame", path, &frame));
    key->time = frame / fps;
  }
  bool has_matrix = j.contains("matrix"), has_lookat = j.contains("lookat");
  bool has_trs = j.contains("translate") || j.contains("rotate") || j.contains("scale");
  if (int(has_matrix) + int(has_lookat) + int(has_trs) != 1)
    return r.error(path, "needs exactly one of 'matrix', 'lookat' or translate/rotate/scale");
  if (has_matrix) {
    std::vector<double> m;
    GDVR_RETURN_IF_ERROR(r.get_vec(j["matrix"], path + ".matrix", 16, &m));
    Matrix4 mat;
    for (int i = 0; i < 16; ++i) mat.m[i / 4][i % 4] = m[i];
    if (!Transform::from_matrix(mat, &key->to_world)) return r.error(path + ".matrix", "singular or not finite");
  } else if (has_lookat) {
    const json& l = j["lookat"];
    std::string lp = path + ".lookat";
    GDVR_RETURN_IF_ERROR(r.check_object(l, lp, {"origin", "target", "up"}));
    std::vector<double> o, t, u = {0, 1, 0};
    if (!l.contains("origin") || !l.contains("target")) return r.error(lp, "needs 'origin' and 'target'");
    GDVR_RETURN_IF_ERROR(r.get_vec(l["origin"], lp + ".origin", 3, &o));
    GDVR_RETURN_IF_ERROR(r.get_vec(l["target"], lp + ".target", 3, &t));
    if (l.contains("up")) GDVR_RETURN_IF_ERROR(r.get_vec(l["up"], lp + ".up", 3, &u));
    if (!Transform::look_at(to_vec3f(o), to_vec3f(t), to_vec3f(u), &key->to_world))
      return r.error(lp, "degenerate (origin equals target, or up parallel to the view direction)");
  } else {
    // to_world = translate * rotate * scale: scale first, as Mitsuba chains them.
    Transform t;
    if (j.contains("scale")) {
      std::vector<double> s;
      GDVR_RETURN_IF_ERROR(r.get_vec(j["scale"], path + ".scale", 3, &s));
      if (s[0] == 0 || s[1] == 0 || s[2] == 0) return r.error(path + ".scale", "zero scale is singular");
      t = Transform::scale(to_vec3f(s));
    }
    if (j.contains("rotate")) {
      const json& rj = j["rotate"];
      std::string rp = path + ".rotate";
      GDVR_RETURN_IF_ERROR(r.check_object(rj, rp, {"axis", "angle"}));
      std::vector<double> axis;
      double angle = 0;
      // Protobuf JSON omits a zero angle, so only the axis is required.
      if (!rj.contains("axis")) return r.error(rp, "needs 'axis' (and 'angle' in degrees)");
      GDVR_RETURN_IF_ERROR(r.get_vec(rj["axis"], rp + ".axis", 3, &axis));
      GDVR_RETURN_IF_ERROR(r.opt(rj, "angle", rp, &angle));
      if (axis[0] == 0 && axis[1] == 0 && axis[2] == 0) return r.error(rp + ".axis", "must be non-zero");
      t = Transform::rotate(to_vec3f(axis), float(angle)) * t;
    }
    if (j.contains("translate")) {
      std::vector<double> d;
      GDVR_RETURN_IF_ERROR(r.get_vec(j["translate"], path + ".translate", 3, &d));
      t = Transform::translate(to_vec3f(d)) * t;
    }
    key->to_world = t;
  }
  // Every form must pass the test the 'matrix' form gets (finite, not
  // numerically singular), or job_to_json would print a key that does not
  // parse again (found by fuzz_job_spec: "scale": [1.1e20, 1, 1]).
  Transform check;
  if (!Transform::from_matrix(key->to_world.matrix(), &check))
    return r.error(path, "the transform is singular, not finite or too ill-conditioned (scales differing by more than 1e14)");
  return Status::Ok();
}

Status parse_tracks(const JsonReader& r, const json& j, const std::string& path, double fps, Animation* anim) {
  if (!j.is_array()) return r.error(path, "must be an array");
  for (size_t i = 0; i < j.size(); ++i) {
    std::string tp = path + "[" + std::to_string(i) + "]";
    const json& tj = j[i];
    GDVR_RETURN_IF_ERROR(r.check_object(tj, tp, {"target", "interpolation", "keys"}));
    Track track;
    std::string interp = "linear";
    GDVR_RETURN_IF_ERROR(r.opt(tj, "target", tp, &track.target));
    GDVR_RETURN_IF_ERROR(r.opt(tj, "interpolation", tp, &interp));
    if (track.target.empty()) return r.error(tp + ".target", "missing");
    if (interp == "step") track.interpolation = Interpolation::kStep;
    else if (interp == "linear" || interp.empty()) track.interpolation = Interpolation::kLinear;
    else if (interp == "cubic") track.interpolation = Interpolation::kCubic;
    else return r.error(tp + ".interpolation", "must be step, linear or cubic, not '" + echo_text(interp) + "'");
    if (!tj.contains("keys") || !tj["keys"].is_array() || tj["keys"].empty())
      return r.error(tp + ".keys", "must be a non-empty array");
    const json& keys = tj["keys"];
    for (size_t k = 0; k < keys.size(); ++k) {
      Keyframe key;
      std::string kp = tp + ".keys[" + std::to_string(k) + "]";
      GDVR_RETURN_IF_ERROR(parse_keyframe(r, keys[k], kp, fps, &key));
      if (!track.keys.empty() && !(key.time > track.keys.back().time))
        return r.error(kp, "key times must be strictly increasing");
      track.keys.push_back(key);
    }
    anim->tracks.push_back(std::move(track));
  }
  return Status::Ok();
}

const char* interpolation_name(Interpolation i) {
  switch (i) {
    case Interpolation::kStep: return "step";
    case Interpolation::kLinear: return "linear";
    case Interpolation::kCubic: return "cubic";
  }
  return "linear";
}

}  // namespace

Expected<std::vector<int>> parse_frame_range(const std::string& text, size_t max_frames) {
  std::set<int> frames;
  size_t limit = max_frames ? std::min(max_frames, kHardFrameLimit) : kHardFrameLimit;
  std::string all = trim(text);
  if (all.empty()) return invalid_argument("frame range is empty");
  const long long kMaxFrame = std::numeric_limits<int>::max();
  // Frames named so far, counting every token in full (an upper bound when
  // tokens overlap), so a huge range is refused before it is expanded.
  long long named = 0;
  size_t start = 0;
  while (start <= all.size()) {
    size_t comma = all.find(',', start);
    if (comma == std::string::npos) comma = all.size();
    std::string token = trim(all.substr(start, comma - start));
    start = comma + 1;
    auto bad = [&](const std::string& why) {
      return invalid_argument("frame range '" + echo_text(text) + "': token '" + echo_text(token) + "': " + why);
    };
    if (token.empty()) return bad("empty");
    std::string range = token, step_text;
    size_t x = token.find_first_of("xX");
    if (x != std::string::npos) {
      range = trim(token.substr(0, x));
      step_text = trim(token.substr(x + 1));
    }
    long long first = 0, last = 0, step = 1;
    size_t dash = range.find('-', 1);  // a leading '-' would be a sign, caught below
    if (dash == std::string::npos) {
      if (!parse_uint(range, &first)) return bad("not a non-negative frame number");
      last = first;
      if (x != std::string::npos) return bad("a step needs a range (\"a-bxs\")");
    } else {
      std::string a = trim(range.substr(0, dash)), b = trim(range.substr(dash + 1));
      if (!parse_uint(a, &first)) return bad("range start is not a non-negative frame number");
      if (!parse_uint(b, &last)) return bad("range end is not a non-negative frame number");
      if (last < first) return bad("range end is before its start");
    }
    if (first > kMaxFrame || last > kMaxFrame)
      return bad("frame number too large (the largest is " + std::to_string(kMaxFrame) + ")");
    if (x != std::string::npos && !parse_uint(step_text, &step)) return bad("step is not a positive integer");
    if (step <= 0) return bad("step must be positive");
    named += (last - first) / step + 1;
    if (named > (long long)limit)
      return resource_exhausted("frame range '" + echo_text(text) + "' is too large: it names " +
                                std::to_string(named) + " frames, over the limit of " + std::to_string(limit));
    for (long long f = first; f <= last; f += step) frames.insert(int(f));
    if (comma == all.size()) break;
  }
  return std::vector<int>(frames.begin(), frames.end());
}

Expected<JobSpec> parse_job_json(const std::string& json_text, const std::string& origin) {
  json j;
  try {
    j = json::parse(json_text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for numbers like 1E99999
    // The parser's message quotes the last token read, which may be huge.
    return invalid_argument(origin + ": not valid JSON: " + echo_text(e.what(), 2 * kEchoMaxChars));
  }
  JsonReader r(origin);
  const std::string p = "job";
  GDVR_RETURN_IF_ERROR(r.check_object(j, p, {"scene", "frames", "fps", "width", "height", "spp", "time_budget_s", "seed",
                                             "integrator", "shift", "reconstruction", "params", "animation", "tracks",
                                             "outputs", "priority", "reference", "direct_light", "temporal_shift"}));
  JobSpec job;
  GDVR_RETURN_IF_ERROR(r.opt(j, "scene", p, &job.scene));
  GDVR_RETURN_IF_ERROR(r.opt(j, "frames", p, &job.frames));
  GDVR_RETURN_IF_ERROR(r.opt(j, "fps", p, &job.fps));
  GDVR_RETURN_IF_ERROR(r.opt(j, "width", p, &job.width));
  GDVR_RETURN_IF_ERROR(r.opt(j, "height", p, &job.height));
  GDVR_RETURN_IF_ERROR(r.opt(j, "spp", p, &job.spp));
  GDVR_RETURN_IF_ERROR(r.opt(j, "time_budget_s", p, &job.time_budget_s));
  GDVR_RETURN_IF_ERROR(r.opt(j, "seed", p, &job.seed));
  GDVR_RETURN_IF_ERROR(r.opt_name(j, "integrator", p, kIntegratorNames, &job.integrator));
  GDVR_RETURN_IF_ERROR(r.opt_name(j, "shift", p, kShiftMappingNames, &job.shift));
  GDVR_RETURN_IF_ERROR(r.opt_name(j, "temporal_shift", p, kTemporalShiftNames, &job.temporal_shift));
  GDVR_RETURN_IF_ERROR(r.opt(j, "priority", p, &job.priority));
  GDVR_RETURN_IF_ERROR(r.opt(j, "reference", p, &job.reference));

  if (j.contains("reconstruction")) {
    const json& rj = j["reconstruction"];
    std::string rp = p + ".reconstruction";
    GDVR_RETURN_IF_ERROR(r.check_object(rj, rp, {"method", "alpha", "window", "tile_size", "term_weights", "clamp_negative",
                                                     "data_term"}));
    ReconstructionSpec& rs = job.reconstruction;
    GDVR_RETURN_IF_ERROR(r.opt_name(rj, "method", rp, kReconMethodNames, &rs.method));
    GDVR_RETURN_IF_ERROR(r.opt(rj, "alpha", rp, &rs.alpha));
    GDVR_RETURN_IF_ERROR(r.opt(rj, "window", rp, &rs.window));
    GDVR_RETURN_IF_ERROR(r.opt(rj, "tile_size", rp, &rs.tile_size));
    GDVR_RETURN_IF_ERROR(r.opt(rj, "clamp_negative", rp, &rs.clamp_negative));
    GDVR_RETURN_IF_ERROR(r.opt_name(rj, "data_term", rp, kDataTermNames, &rs.data_term));
    if (rj.contains("term_weights") && !rj["term_weights"].is_null() &&
        !(rj["term_weights"].is_array() && rj["term_weights"].empty()))  // protobuf JSON: [] or absent = unset
      GDVR_RETURN_IF_ERROR(r.get_vec(rj["term_weights"], rp + ".term_weights", kTermCount, &rs.term_weights));
  }
  if (j.contains("direct_light")) {
    const json& dj = j["direct_light"];
    std::string dp = p + ".direct_light";
    GDVR_RETURN_IF_ERROR(r.check_object(dj, dp, {"strata", "edge_strata"}));
    GDVR_RETURN_IF_ERROR(r.opt(dj, "strata", dp, &job.direct_light.strata));
    GDVR_RETURN_IF_ERROR(r.opt(dj, "edge_strata", dp, &job.direct_light.edge_strata));
  }
  if (j.contains("params")) {
    const json& pj = j["params"];
    if (!pj.is_object()) return r.error(p + ".params", "must be an object of strings");
    for (auto it = pj.begin(); it != pj.end(); ++it) {
      std::string v;
      // Numbers are accepted for convenience ("spp": 64); Mitsuba substitutes text.
      if (it->is_number_integer()) v = std::to_string(it->get<long long>());
      else if (it->is_number_float()) v = it->dump();
      else GDVR_RETURN_IF_ERROR(r.get(*it, p + ".params." + it.key(), &v));
      job.params[it.key()] = v;
    }
  }
  if (j.contains("outputs")) {
    const json& oj = j["outputs"];
    std::string op = p + ".outputs";
    GDVR_RETURN_IF_ERROR(r.check_object(oj, op, {"exr_layers", "exr_compression", "previews", "video_codec", "ocio_display", "ocio_view"}));
    OutputSpec& o = job.outputs;
    if (oj.contains("exr_layers")) {
      const json& lj = oj["exr_layers"];
      if (!lj.is_array()) return r.error(op + ".exr_layers", "must be an array of strings");
      for (size_t i = 0; i < lj.size(); ++i) {
        std::string layer;
        GDVR_RETURN_IF_ERROR(r.get(lj[i], op + ".exr_layers[" + std::to_string(i) + "]", &layer));
        o.exr_layers.push_back(layer);
      }
    }
    GDVR_RETURN_IF_ERROR(r.opt(oj, "exr_compression", op, &o.exr_compression));
    GDVR_RETURN_IF_ERROR(r.opt(oj, "previews", op, &o.previews));
    GDVR_RETURN_IF_ERROR(r.opt(oj, "video_codec", op, &o.video_codec));
    GDVR_RETURN_IF_ERROR(r.opt(oj, "ocio_display", op, &o.ocio_display));
    GDVR_RETURN_IF_ERROR(r.opt(oj, "ocio_view", op, &o.ocio_view));
  }
  // Values, before the tracks: a keyframe's `frame` converts with the fps.
  if (Status st = validate(job); !st.ok()) return Status(st.code(), origin + ": " + st.message());
  if (j.contains("animation") && j.contains("tracks")) return r.error(p, "give tracks under 'animation' or at the top level, not both");
  if (j.contains("animation")) {
    const json& aj = j["animation"];
    GDVR_RETURN_IF_ERROR(r.check_object(aj, p + ".animation", {"tracks"}));
    if (aj.contains("tracks")) GDVR_RETURN_IF_ERROR(parse_tracks(r, aj["tracks"], p + ".animation.tracks", job.fps, &job.animation));
  }
  if (j.contains("tracks")) GDVR_RETURN_IF_ERROR(parse_tracks(r, j["tracks"], p + ".tracks", job.fps, &job.animation));
  return job;
}

std::string job_to_json(const JobSpec& job) {
  json j;
  j["scene"] = job.scene;
  j["frames"] = job.frames;
  j["fps"] = job.fps;
  j["width"] = job.width;
  j["height"] = job.height;
  j["spp"] = job.spp;
  j["time_budget_s"] = job.time_budget_s;
  // Protobuf JSON spells uint64 as a string; parse_job_json reads both.
  j["seed"] = std::to_string(job.seed);
  j["integrator"] = integrator_name(job.integrator);
  j["shift"] = shift_mapping_name(job.shift);
  j["temporal_shift"] = temporal_shift_name(job.temporal_shift);
  j["reconstruction"] = {{"method", recon_method_name(job.reconstruction.method)},
                         {"alpha", job.reconstruction.alpha},
                         {"window", job.reconstruction.window},
                         {"tile_size", job.reconstruction.tile_size},
                         {"clamp_negative", job.reconstruction.clamp_negative},
                         {"data_term", data_term_name(job.reconstruction.data_term)}};
  if (!job.reconstruction.term_weights.empty()) j["reconstruction"]["term_weights"] = job.reconstruction.term_weights;
  j["direct_light"] = json::object();
  if (job.direct_light.strata) j["direct_light"]["strata"] = *job.direct_light.strata;
  if (job.direct_light.edge_strata) j["direct_light"]["edge_strata"] = *job.direct_light.edge_strata;
  j["params"] = json::object();
  for (const auto& [k, v] : job.params) j["params"][k] = v;
  json tracks = json::array();
  for (const Track& t : job.animation.tracks) {
    json keys = json::array();
    for (const Keyframe& k : t.keys) {
      json m = json::array();
      for (int i = 0; i < 16; ++i) m.push_back(k.to_world.matrix().m[i / 4][i % 4]);
      keys.push_back({{"time", k.time}, {"matrix", m}});
    }
    tracks.push_back({{"target", t.target}, {"interpolation", interpolation_name(t.interpolation)}, {"keys", keys}});
  }
  j["animation"] = {{"tracks", tracks}};
  j["outputs"] = {{"exr_layers", job.outputs.exr_layers},
                  {"exr_compression", job.outputs.exr_compression},
                  {"previews", job.outputs.previews},
                  {"video_codec", job.outputs.video_codec},
                  {"ocio_display", job.outputs.ocio_display},
                  {"ocio_view", job.outputs.ocio_view}};
  j["priority"] = job.priority;
  j["reference"] = job.reference;
  return j.dump(2);
}

}  // namespace gdvr
