#include "server/client_message.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "core/util/echo_text.h"

namespace gdvr::server {
namespace fs = std::filesystem;

namespace {

// The spellings of a folder a message may contain: as configured, absolute,
// and resolved (symlinks, "..").
std::vector<std::string> spellings(const std::string& path) {
  std::vector<std::string> out;
  if (path.empty()) return out;
  std::error_code ec;
  auto add = [&](fs::path p) {
    std::string s = p.lexically_normal().string();
    while (s.size() > 1 && s.back() == '/') s.pop_back();
    if (!s.empty() && s != "." && std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  };
  add(path);
  add(fs::absolute(path, ec));
  fs::path canonical = fs::weakly_canonical(path, ec);
  if (!ec) add(canonical);
  return out;
}

// What may continue a path component (anything but the delimiters around
// a path in a message).
bool is_path_char(char c) { return c != ' ' && c != '\'' && c != '"' && c != ':' && c != ',' && c != ')'; }

}  // namespace

ClientMessageFilter::ClientMessageFilter(const ServerConfig& config) {
  // Replacement "": the path inside becomes relative ("<root>/cbox/x.xml"
  // -> "cbox/x.xml"); the folder itself is named by its role.
  auto add = [&](const std::string& folder, const std::string& inside, const std::string& itself) {
    for (const std::string& s : spellings(folder)) {
      replacements_.push_back({s + "/", inside});
      replacements_.push_back({s, itself});
    }
  };
  add(config.uploads.root, "uploads/", "<upload folder>");
  add(config.output_root, "<output-root>/", "<output-root>");
  add(config.asset_root, "", "<asset-root>");
  const char* ocio_env = std::getenv("OCIO");
  for (const std::string& ocio : {config.ocio_config, std::string(ocio_env ? ocio_env : "")}) {
    if (ocio.empty()) continue;
    fs::path p(ocio);
    for (const std::string& s : spellings(ocio)) replacements_.push_back({s, "<ocio-config>"});
    add(p.parent_path().string(), "<ocio-config-dir>/", "<ocio-config-dir>");
  }
  if (!config.db_path.empty())
    for (const std::string& s : spellings(config.db_path)) replacements_.push_back({s, "<job-db>"});
  // Longest first, so the upload root inside the output root wins.
  std::stable_sort(replacements_.begin(), replacements_.end(),
                   [](const auto& a, const auto& b) { return a.first.size() > b.first.size(); });
}

std::string ClientMessageFilter::operator()(const std::string& message) const {
  std::string text = message;
  for (const auto& [from, to] : replacements_) {
    if (from.size() < 2) continue;  // "/" alone is no folder to hide
    size_t pos = 0;
    while ((pos = text.find(from, pos)) != std::string::npos) {
      // Whole components only: "/srv/assets" must not match "/srv/assets2"
      // ("/srv/assets/..." was replaced already, by its longer entry).
      size_t end = pos + from.size();
      bool whole = from.back() == '/' || end == text.size() || !is_path_char(text[end]);
      if (!whole) {
        pos = end;
        continue;
      }
      text.replace(pos, from.size(), to);
      pos += to.size();
    }
  }
  text = escape_control_chars(text);
  if (text.size() <= kMaxClientMessageChars) return text;
  // Head and tail: the field at fault comes first, the reason often last.
  const size_t head = kMaxClientMessageChars * 2 / 3, tail = kMaxClientMessageChars / 4;
  size_t h = head, t = text.size() - tail;
  while (h > 0 && (static_cast<unsigned char>(text[h]) & 0xC0) == 0x80) --h;
  while (t < text.size() && (static_cast<unsigned char>(text[t]) & 0xC0) == 0x80) ++t;
  return text.substr(0, h) + "\xE2\x80\xA6 (" + std::to_string(text.size() - h - (text.size() - t)) +
         " characters left out) \xE2\x80\xA6" + text.substr(t);
}

}  // namespace gdvr::server
