#include "core/io/shipped_ocio_config.h"

#include <filesystem>
#include <vector>

namespace fs = std::filesystem;

namespace gdvr {

std::string find_shipped_ocio_config() {
  std::vector<fs::path> candidates;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path dir = exe.parent_path();
    candidates = {dir / "../share/gdvr/ocio/config.ocio", dir / "../../data/ocio/config.ocio",
                  dir / "../data/ocio/config.ocio"};
  }
#ifdef GDVR_CONFIGURED_SOURCE_DIR
  candidates.push_back(fs::path(GDVR_CONFIGURED_SOURCE_DIR) / "data/ocio/config.ocio");
#endif
  for (const fs::path& candidate : candidates)
    if (fs::exists(candidate, ec)) return fs::weakly_canonical(candidate, ec).string();
  return "data/ocio/config.ocio";
}

}  // namespace gdvr
