// The images HybridEffects names for an effect that is off (or not sized yet): 1x1 and constant, so an engine
// writes its descriptor sets once and a disabled effect reads as "no effect" (white visibility and AO, zero
// reflection and local-light radiance). Cleared by the first record() that needs them.
#pragma once

#include "gpu_memory.h"

namespace rb {

class NeutralImages {
 public:
  // Creates the two images (no-op when they exist); their contents are undefined until recordInit().
  Status ensure(Context& ctx);
  // Clears them and leaves them in SHADER_READ_ONLY_OPTIMAL, once: later calls record nothing.
  void recordInit(Context& ctx, VkCommandBuffer cmd);
  bool exist() const { return white_.image != VK_NULL_HANDLE; }
  // R16_SFLOAT 1.0: visibility and AO of an effect that is off.
  const GpuImage& white() const { return white_; }
  // R16G16B16A16_SFLOAT (0, 0, 0, 0): reflection and local-light radiance of an effect that is off.
  const GpuImage& black() const { return black_; }
  // Hands both to the context's deferred release.
  void retire(Context& ctx);

 private:
  GpuImage white_, black_;
  bool initialised_ = false;
};

}  // namespace rb
