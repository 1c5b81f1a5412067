// HybridEffectsDesc's validation (hybrid_effects.h): every field by name, before HybridEffects::create() or
// setDesc() changes anything. Used by hybrid_effects.cpp alone.
#pragma once

#include <raybridge/hybrid_effects.h>

namespace rb {

// An error naming the first field out of range and what to do, or success.
Status validateHybridEffectsDesc(const HybridEffectsDesc& d);

}  // namespace rb
