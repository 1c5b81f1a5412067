// raybridge-render --dump and raybridge-effects-bench: copies the pre-pass depth, the normal the passes used and
// the effect images (sun visibility, AO, reflection; raw and denoised) of one frame into host memory, recorded from
// inside the pre-pass hook (the engine reads back only its final images). Vulkan functions come from the engine's
// vkGetInstanceProcAddr, like the SDK's.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "sample_engine/engine.h"

namespace rbRender {

struct CapturedFrame {
  uint32_t width = 0, height = 0;
  std::vector<float> depth;                          // D32 depth buffer values, rows from the top
  std::vector<float> normal;                         // RGBA per pixel (xyz = world normal, w = roughness or metallic)
  std::map<std::string, std::vector<float>> images;  // by name: `channels` floats per pixel
};

// An effect image to copy: R16_SFLOAT (channels 1) or R16G16B16A16_SFLOAT (channels 4), or R32_SFLOAT with
// float32, in SHADER_READ_ONLY_OPTIMAL, the size of the pre-pass.
struct CaptureImage {
  std::string name;
  VkImage image = VK_NULL_HANDLE;
  uint32_t channels = 1;
  bool float32 = false;  // 32-bit floats (e.g. the ray-traced mode's distances) instead of 16-bit ones
};

class FrameCapture {
 public:
  static sample_engine::Result<std::unique_ptr<FrameCapture>> create(sample_engine::Engine& engine);
  ~FrameCapture();

  // Records the copies into the hook's command buffer and restores every image's layout. Images whose
  // handle is VK_NULL_HANDLE are skipped; the same VkImage under two names is copied once.
  sample_engine::Status record(const sample_engine::PrepassHookInfo& info, const sample_engine::PassImage& normal,
                               const std::vector<CaptureImage>& images);
  // After the frame finished (Engine::waitIdle): the copied data.
  CapturedFrame read() const;

  struct Impl;

 private:
  explicit FrameCapture(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rbRender
