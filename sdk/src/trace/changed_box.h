// The one test of a ChangedBox (effects.h) that every taker of one runs: HybridFrame::changedBoxes (hybrid_effects.cpp)
// and ReflectionSettings::changedBoxes / relitBoxes (reflection_pass.cpp).
//
// Thread safety: a pure function.
#pragma once

#include <raybridge/effects.h>

#include <cmath>

namespace rb {

// The first axis on which `b` is not a box (a corner not finite, or min > max), or -1 when it is one.
inline int invalidChangedBoxAxis(const ChangedBox& b) {
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(b.min[k]) || !std::isfinite(b.max[k]) || b.min[k] > b.max[k]) return k;
  }
  return -1;
}

}  // namespace rb
