// What other passes read of a ManyLightPass: the GPU light list it uploaded this frame (reflection hits are lit
// by the same lights), in the layout of shaders/light_list.glsl.
#pragma once

#include <raybridge/many_light_pass.h>

#include <cstdint>

namespace rb {

// Mirrors GpuLight in shaders/light_list.glsl (std430). Filled on the host by ManyLightPass::record.
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

namespace internal {

struct LightListView {
  VkBuffer buffer = VK_NULL_HANDLE;  // device-local GpuLight[count], readable by ray tracing shaders after record
  uint32_t count = 0;
  uint64_t frame = UINT64_MAX;  // Context::frameIndex() of the latest record(); UINT64_MAX = never recorded
  double originOffset[3] = {0.0, 0.0, 0.0};  // the TLAS space the positions are in
};

struct ManyLightPassAccess {
  static LightListView lightList(const ManyLightPass& pass);
};
inline LightListView lightList(const ManyLightPass& pass) { return ManyLightPassAccess::lightList(pass); }

}  // namespace internal
}  // namespace rb
