#include "core/util/path_confinement.h"

#include <algorithm>
#include <system_error>

namespace gdvr {
namespace {

namespace fs = std::filesystem;

// Absolute, resolved as far as it exists, without a trailing separator; empty
// when that cannot be done (no error escapes: fs calls take error codes).
fs::path resolved(const fs::path& path) {
  if (path.empty()) return {};
  std::error_code ec;
  const fs::path absolute = fs::absolute(path, ec);
  if (ec) return {};
  fs::path canonical = fs::weakly_canonical(absolute, ec);
  if (ec || canonical.empty()) return {};
  // "dir/" ends in an empty component, which a prefix test would demand of the path.
  return canonical.has_filename() ? canonical : canonical.parent_path();
}

}  // namespace

bool is_inside_root(const fs::path& path, const fs::path& root) {
  const fs::path p = resolved(path), r = resolved(root);
  if (p.empty() || r.empty()) return false;
  return std::mismatch(r.begin(), r.end(), p.begin(), p.end()).first == r.end();
}

}  // namespace gdvr
