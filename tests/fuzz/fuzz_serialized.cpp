// libFuzzer target: Mitsuba's .serialized reader. The shape index is the
// first byte (mod 4), the file the rest.
#include <string>

#include "core/scene/serialized_reader.h"
#include "tests/fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > gdvr::fuzz::kMaxInput) return 0;
  const int shape_index = data[0] % 4;
  auto mesh = gdvr::parse_serialized(std::string(reinterpret_cast<const char*>(data) + 1, size - 1), shape_index,
                                     "fuzz.serialized");
  if (mesh.ok()) gdvr::fuzz::check_reader_output(std::move(mesh.value()));
  return 0;
}
