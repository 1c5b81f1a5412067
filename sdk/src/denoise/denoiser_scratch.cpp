#include "denoiser_scratch.h"

#include "context_impl.h"

namespace rb {

namespace {

struct KindSpec {
  VkFormat format;
  const char* name;
};
constexpr KindSpec kKinds[DenoiserScratch::Impl::kKindCount] = {
    {VK_FORMAT_R16G16_SFLOAT, "denoiser spatial A"},
    {VK_FORMAT_R16G16_SFLOAT, "denoiser spatial B"},
    {VK_FORMAT_R16G16B16A16_SFLOAT, "denoiser RGB spatial A"},
    {VK_FORMAT_R32G32_UINT, "denoiser RGB guide"},
};

}  // namespace

DenoiserScratch::Impl::Impl(Context& c) : ctx(c), owner(internal::contextImpl(c).memoryOwner) {}

DenoiserScratch::Impl::~Impl() {
  for (GpuImage& img : images) retireImage(ctx, img);
}

Result<const GpuImage*> DenoiserScratch::Impl::image(Kind kind, uint32_t width, uint32_t height) {
  GpuImage& img = images[kind];
  if (img.valid() && img.width == width && img.height == height) return &img;
  retireImage(ctx, img);
  const MemoryOwnerScope scope(internal::contextImpl(ctx), owner);
  Result<GpuImage> made = createStorageImage(ctx, width, height, kKinds[kind].format, VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                                             MemoryCategory::PassImages, kKinds[kind].name);
  if (!made) return made.error();
  img = made.value();
  return &img;
}

void DenoiserScratch::Impl::release(Kind kind) { retireImage(ctx, images[kind]); }

Result<std::unique_ptr<DenoiserScratch>> DenoiserScratch::create(Context& context) {
  return std::unique_ptr<DenoiserScratch>(new DenoiserScratch(std::make_unique<Impl>(context)));
}

DenoiserScratch::DenoiserScratch(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
DenoiserScratch::~DenoiserScratch() = default;

}  // namespace rb
