// libFuzzer target: the PLY reader (ASCII and binary).
#include <string>

#include "core/scene/ply_reader.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > gdvr::fuzz::kMaxInput) return 0;
  auto mesh = gdvr::parse_ply(std::string(reinterpret_cast<const char*>(data), size), "fuzz.ply");
  if (mesh.ok()) gdvr::fuzz::check_reader_output(std::move(mesh.value()));
  return 0;
}
