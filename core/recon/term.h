// The six terms of the temporal gradient-domain objective (Manzi et al. 2016;
// docs/reconstruction.md):
// one primal and five finite-difference constraints per pixel and frame.
#pragma once

#include <array>

namespace gdvr {

enum class Term : int { kPrimal = 0, kDx, kDy, kDt, kDxdt, kDydt };
constexpr int kTermCount = 6;

constexpr std::array<Term, kTermCount> kAllTerms = {Term::kPrimal, Term::kDx,   Term::kDy,
                                                    Term::kDt,     Term::kDxdt, Term::kDydt};

inline const char* term_name(Term t) {
  switch (t) {
    case Term::kPrimal: return "primal";
    case Term::kDx: return "dx";
    case Term::kDy: return "dy";
    case Term::kDt: return "dt";
    case Term::kDxdt: return "dxdt";
    case Term::kDydt: return "dydt";
  }
  return "?";
}

inline constexpr int term_index(Term t) { return static_cast<int>(t); }

// Temporal terms couple frame t with frame t+1, so they vanish on the last
// frame of a window (constraints leaving the window are dropped: docs/reconstruction.md).
inline constexpr bool is_temporal(Term t) { return t == Term::kDt || t == Term::kDxdt || t == Term::kDydt; }
// Terms that difference along x (need p+e_x) or y (need p+e_y).
inline constexpr bool uses_x_neighbour(Term t) { return t == Term::kDx || t == Term::kDxdt; }
inline constexpr bool uses_y_neighbour(Term t) { return t == Term::kDy || t == Term::kDydt; }

}  // namespace gdvr
