// libFuzzer target: the Wavefront OBJ reader.
#include <sstream>
#include <string>

#include "core/scene/obj_reader.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > gdvr::fuzz::kMaxInput) return 0;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  auto mesh = gdvr::parse_obj(in, "fuzz.obj");
  if (mesh.ok()) gdvr::fuzz::check_reader_output(std::move(mesh.value()));
  return 0;
}
