// What a client is shown of an error (a gRPC status message, a job's failure
// reason). Three rules, applied to every such text in one place:
//  - server paths are shown relative to the folder they belong to: a file
//    under the asset root by its asset-root-relative name, an uploaded file
//    as "uploads/<hash>/...", job outputs and the OCIO config by names
//    without the server's folders. The server log keeps the absolute paths.
//  - control characters and NUL are escaped;
//  - the text is bounded (kMaxClientMessageChars, head and tail kept): a gRPC
//    status travels in a header, and one over the client's 16 KiB metadata
//    limit reaches it as RESOURCE_EXHAUSTED "Stream removed" instead of the
//    error. Inputs echoed inside messages are cut at their source already
//    (core/util/echo_text.h); this bound is the backstop.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "server/config.h"

namespace gdvr::server {

constexpr size_t kMaxClientMessageChars = 2000;

class ClientMessageFilter {
 public:
  explicit ClientMessageFilter(const ServerConfig& config);
  std::string operator()(const std::string& message) const;

 private:
  // (absolute prefix, what a client sees instead), longest prefix first.
  std::vector<std::pair<std::string, std::string>> replacements_;
};

}  // namespace gdvr::server
