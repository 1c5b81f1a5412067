// Half-resolution tracing for a G-buffer pass (AO, reflections): the image the pass traces into, one sample per
// 2x2 block of the G-buffer (shaders/half_resolution.glsl), and the depth-aware upsample that writes the pass's
// full-resolution output from it (shaders/upsample_depth_aware.glsl). Holds nothing until first used, and no
// image while the pass traces at full resolution.
#pragma once

#include <raybridge/gbuffer.h>

#include "compute_pipeline.h"
#include "pass_constants.h"
#include "pass_images.h"

namespace rb {

class HalfResolution {
 public:
  enum class Signal : uint8_t {
    Ao,          // R16_SFLOAT open fraction (ao.rgen)
    Reflection,  // R16G16B16A16_SFLOAT radiance, a = coverage (reflect.rgen)
  };
  explicit HalfResolution(Signal signal) : signal_(signal) {}

  // Makes the sample image for a width x height G-buffer (an old one of another size is retired) and, on first
  // use, the upsample pipeline.
  Status ensure(Context& ctx, uint32_t width, uint32_t height);
  // Retires the sample image (the pass traces at full resolution again); the pipeline stays for a later use.
  void releaseImage(Context& ctx);
  // Retires the image and the pipeline (the pass is destroyed; frames in flight may still use them).
  void retire(Context& ctx);

  // The launch: one invocation per sample, ceil(width / 2) x ceil(height / 2).
  uint32_t width() const { return images_[0].width; }
  uint32_t height() const { return images_[0].height; }
  VkImageView samplesView() const { return images_[0].view; }
  // Makes the sample image writable by the ray generation shader (last frame's samples discarded).
  void beginTrace(Context& ctx, VkCommandBuffer cmd) { images_.beginWrite(ctx, cmd); }
  // Makes the samples readable and upsamples them into `output` (full resolution, GENERAL, writable by compute
  // shaders). `traced`: the constants the pass traced with (their frame chose the samples); `roughnessThreshold`:
  // reflections' (the pixels that get no coverage).
  void upsample(Context& ctx, VkCommandBuffer cmd, const GBufferDesc& g, VkSampler sampler,
                const GBufferConstants& traced, float roughnessThreshold, VkImageView output);

 private:
  Signal signal_;
  ComputePipeline pipeline_;
  PassImages images_;
};

}  // namespace rb
