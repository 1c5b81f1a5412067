// The tools' --reset-follow-up N on a HybridEffectsDesc: one mapping for raybridge-render and the effects bench.
// N frames of follow-ups (HybridEffectsDesc::resetFollowUpFrames), 0 = none (disableResetFollowUp, since the SDK
// reads a 0 in resetFollowUpFrames as its default); not given = the SDK's default.
//
// Thread safety: a pure function.
#pragma once

#include <raybridge/hybrid_effects.h>

#include <cstdint>
#include <optional>

namespace rbTools {

inline void applyResetFollowUp(rb::HybridEffectsDesc& desc, std::optional<uint32_t> frames) {
  if (!frames) return;
  desc.resetFollowUpFrames = *frames;
  desc.disableResetFollowUp = *frames == 0u;
}

}  // namespace rbTools
