// raybridge-render only: copies the pre-pass depth, the normal the passes used and the sun-visibility image
// of one frame into host memory, recorded from inside the pre-pass hook (the engine reads back only its
// final images). Vulkan functions come from the engine's vkGetInstanceProcAddr, like the SDK's.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "sample_engine/engine.h"

namespace rbRender {

struct CapturedFrame {
  uint32_t width = 0, height = 0;
  std::vector<float> depth;       // D32 depth buffer values, rows from the top
  std::vector<float> normal;      // RGBA per pixel (xyz = world normal, w = roughness or metallic)
  std::vector<float> visibility;  // R16F sun visibility; empty when no visibility image was captured
};

class FrameCapture {
 public:
  static sample_engine::Result<std::unique_ptr<FrameCapture>> create(sample_engine::Engine& engine);
  ~FrameCapture();

  // Records the copies into the hook's command buffer and restores every image's layout. `visibility` may
  // be VK_NULL_HANDLE; when given it is R16_SFLOAT in SHADER_READ_ONLY_OPTIMAL (rb::ShadowOutputs).
  sample_engine::Status record(const sample_engine::PrepassHookInfo& info, const sample_engine::PassImage& normal,
                               VkImage visibility);
  // After the frame finished (Engine::waitIdle): the copied data.
  CapturedFrame read() const;

  struct Impl;

 private:
  explicit FrameCapture(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rbRender
