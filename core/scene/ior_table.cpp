#include "core/scene/ior_table.h"

namespace gdvr {

bool lookup_ior(const std::string& name, float* ior) {
  static const struct { const char* name; float value; } kTable[] = {
      {"vacuum", 1.0f},
      {"helium", 1.000036f},
      {"hydrogen", 1.000132f},
      {"air", 1.000277f},
      {"carbon dioxide", 1.00045f},
      {"water", 1.3330f},
      {"acetone", 1.36f},
      {"ethanol", 1.361f},
      {"carbon tetrachloride", 1.461f},
      {"glycerol", 1.4729f},
      {"benzene", 1.501f},
      {"silicone oil", 1.52045f},
      {"bromine", 1.661f},
      {"water ice", 1.31f},
      {"fused quartz", 1.458f},
      {"pyrex", 1.470f},
      {"acrylic glass", 1.49f},
      {"polypropylene", 1.49f},
      {"bk7", 1.5046f},
      {"sodium chloride", 1.544f},
      {"amber", 1.55f},
      {"pet", 1.5750f},
      {"diamond", 2.419f},
  };
  for (const auto& e : kTable)
    if (name == e.name) {
      *ior = e.value;
      return true;
    }
  return false;
}

}  // namespace gdvr
