// Output images owned by a pass: (re)created at the G-buffer's size, transitioned for writing before the
// pass and to SHADER_READ_ONLY_OPTIMAL after it.
#pragma once

#include <vector>

#include "gpu_memory.h"

namespace rb {

class PassImages {
 public:
  struct Spec {
    VkFormat format;
    const char* name;
  };
  // Recreates the images when the size changed (the old ones are retired: a frame in flight may read them).
  Status ensure(Context& ctx, uint32_t width, uint32_t height, const std::vector<Spec>& specs);
  // Hands every image to the context's deferred release (frames in flight may still use them).
  void retire(Context& ctx);
  // Barrier: previous contents discarded (UNDEFINED -> GENERAL) for ray tracing shader writes.
  void beginWrite(Context& ctx, VkCommandBuffer cmd);
  // Barrier: GENERAL -> SHADER_READ_ONLY_OPTIMAL, visible to fragment, compute and ray tracing shaders.
  void endWrite(Context& ctx, VkCommandBuffer cmd);
  const GpuImage& operator[](size_t i) const { return images_[i]; }
  size_t size() const { return images_.size(); }

 private:
  std::vector<GpuImage> images_;
};

}  // namespace rb
