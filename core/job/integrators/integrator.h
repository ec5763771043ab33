// The integrators a job can name ("integrator" in the job file). Each has its
// runner in this folder (integrator_runner.h): adding one means a value and a
// name here, a runner next to it and its case in make_integrator_runner.
#pragma once

#include <string>

#include "core/util/enum_names.h"
#include "core/util/status.h"

namespace gdvr {

enum class Integrator {
  kPt,    // path tracing (core/render)
  kGpt,   // gradient-domain path tracing, one frame at a time (core/gradient)
  kTgpt,  // temporal gradient-domain path tracing, windows of frames (core/temporal)
};

inline constexpr EnumNames<Integrator, 3> kIntegratorNames = {
    {{Integrator::kPt, "pt"}, {Integrator::kGpt, "gpt"}, {Integrator::kTgpt, "tgpt"}}};

inline const char* integrator_name(Integrator i) { return enum_name(kIntegratorNames, i); }
inline Expected<Integrator> parse_integrator(const std::string& name) {
  return parse_enum_name(kIntegratorNames, name, "integrator");
}

// Whether the integrator samples gradients and reconstructs the final image
// from them (and so keeps directly seen light out of the solve).
inline bool is_gradient_domain(Integrator i) { return i != Integrator::kPt; }

}  // namespace gdvr
