// The GPU light list behind rb::LightList, and behind ManyLightPass::record given the lights themselves: the
// lights checked and converted on the host, a per-frame ring and its copy into the device buffer the shaders read
// (shaders/light_list.glsl's layout). Split in two so a pass can check everything before it records anything:
// stage() checks, converts and allocates; recordUpload() only records.
#pragma once

#include <raybridge/light_list.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "gpu_memory.h"

namespace rb {

// Mirrors GpuLight in shaders/light_list.glsl (std430).
struct GpuLight {
  float position[3];   // point, spot: TLAS space
  float range;         // 0 = unlimited
  float direction[3];  // directional: towards the light; spot: the axis it shines along (unit)
  uint32_t type;       // RB_LIGHT_*
  float intensity[3];  // colour * intensity
  float softness;      // point, spot: radius; directional: tan(angular radius)
  float cosOuter;
  float coneScale;
  float coneOffset;
  float pad0;
};
static_assert(sizeof(GpuLight) == 64);

class LightListBuffer {
 public:
  // Checks `lights` (errors name who + "lights[i]: " and the field), converts them into the TLAS's space and
  // grows the buffers to hold them (at least one light, so that the buffer can be bound). Records nothing.
  Status stage(Context& ctx, std::span<const LightSource> lights, const TlasInfo& tlas, const std::string& who);
  // Copies the staged lights into this frame's ring slot and records their copy into the device buffer, with
  // barriers from last frame's readers and to this frame's (compute and ray tracing shaders).
  void recordUpload(Context& ctx, VkCommandBuffer cmd);
  uint32_t stagedCount() const { return uint32_t(staging_.size()); }
  const LightListInfo& info() const { return info_; }  // of the latest recordUpload()
  void retire(Context& ctx);                           // to the deferred release

 private:
  GpuBuffer ring_, lights_;  // host-visible, one slot of capacity_ lights per frame in flight; its device copy
  uint32_t capacity_ = 0;
  std::vector<GpuLight> staging_;
  double stagedOrigin_[3] = {0.0, 0.0, 0.0};
  LightListInfo info_;
};

// A LightList as a pass reads it: refused, naming `field`, unless it was recorded this frame (`frameIndex`) for
// the TLAS space the pass traces.
Result<LightListInfo> readLightList(const LightList& list, const TlasInfo& tlas, uint64_t frameIndex,
                                    const std::string& field);

}  // namespace rb
