// HybridEffectsDesc's validation (hybrid_effects.h): every field by name, before HybridEffects::create() or
// setDesc() changes anything; and a HybridFrame's, before record() records anything. Used by hybrid_effects.cpp alone.
#pragma once

#include <raybridge/hybrid_effects.h>

namespace rb {

// An error naming the first field out of range and what to do, or success.
Status validateHybridEffectsDesc(const HybridEffectsDesc& d);
// A frame's inputs against the description (record()): the G-buffer's size and hand-over, the reflection G-buffer,
// the light when `lit` (shadows or reflections run), the engine's changed boxes.
Status validateHybridFrame(const HybridEffectsDesc& d, const HybridFrame& frame, bool lit);

}  // namespace rb
