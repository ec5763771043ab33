// Where gdvr's own OCIO config (data/ocio/config.ocio) is, for the command-line
// tools that encode display images (gdvr-farm finalize, gdvr-report).
#pragma once

#include <string>

namespace gdvr {

// The first that exists of: beside an installed binary
// (<prefix>/bin -> <prefix>/share/gdvr/ocio), the source tree of a build
// folder inside it (build/bin/gdvr-farm -> data/ocio), and the source tree
// this binary was configured from (a build folder anywhere else). Otherwise
// the relative "data/ocio/config.ocio", which the OCIO error then names.
std::string find_shipped_ocio_config();

}  // namespace gdvr
