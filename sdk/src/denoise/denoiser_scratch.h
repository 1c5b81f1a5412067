// DenoiserScratch's internals (raybridge/denoiser.h): the transient images of the denoisers that share it, one per
// kind, at the size last asked for.
#pragma once

#include <raybridge/denoiser.h>

#include "context_access.h"
#include "gpu_memory.h"

namespace rb {

struct DenoiserScratch::Impl {
  enum Kind : uint32_t {
    kScalarPing = 0,  // RG16F: the scalar a-trous steps' first image (Denoiser's image 5)
    kScalarPong,      // RG16F: their second, for three steps or more (image 7)
    kRgbPing,         // RGBA16F: the RGB temporal result and a-trous ping (image 4)
    kRgbGuide,        // RG32UI: the RGB a-trous guide (image 6)
    kKindCount
  };
  Context& ctx;
  // The memory owner when the scratch was created (Context::Impl::memoryOwner): its images count to it, whichever
  // denoiser first asks for them.
  uint32_t owner = 0;
  GpuImage images[kKindCount];

  explicit Impl(Context& c);
  ~Impl();  // retires the images: frames in flight may still use them
  // The image of `kind` at width x height, created (or re-created at a new size, the old one retired) when needed.
  Result<const GpuImage*> image(Kind kind, uint32_t width, uint32_t height);
  void release(Kind kind);  // retires the image of `kind`, if any
};

namespace internal {
inline DenoiserScratch::Impl& scratchImpl(DenoiserScratch& s) { return ContextAccess::implOf(s); }
}  // namespace internal

}  // namespace rb
