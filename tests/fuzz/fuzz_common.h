// Shared helpers of the libFuzzer targets (tests/fuzz/run_fuzz.sh builds them
// with clang, -fsanitize=fuzzer,address,undefined). A target returns 0 for
// every input; crashes, sanitizer reports and broken invariants (abort) are
// the findings.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/scene/mesh_repair.h"
#include "core/scene/scene.h"

namespace gdvr::fuzz {

// Fuzz inputs beyond this are not interesting (and slow every iteration).
constexpr size_t kMaxInput = 1 << 16;

inline void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz invariant violated: %s\n", what);
    std::abort();
  }
}

// A mesh a loader hands on must be usable: indices in range, attribute arrays
// empty or one per vertex.
inline void check_mesh(const TriangleMesh& m) {
  check(m.indices.size() % 3 == 0, "index count is a multiple of 3");
  for (uint32_t i : m.indices) check(i < m.positions.size(), "index < vertex count");
  check(m.normals.empty() || m.normals.size() == m.positions.size(), "one normal per vertex");
  check(m.uvs.empty() || m.uvs.size() == m.positions.size(), "one uv per vertex");
}

// The readers return raw file content; the scene loaders pass every mesh
// through validate_and_repair_mesh, which must reject or repair anything
// unusable. Checks that pair as the loaders use it.
inline void check_reader_output(TriangleMesh mesh) {
  MeshRepairReport report;
  if (validate_and_repair_mesh(&mesh, "fuzz", &report).ok()) check_mesh(mesh);
}

}  // namespace gdvr::fuzz
