// GBufferImage::format, ::width and ::height (gbuffer.h), stated for the motion inputs the denoisers and the ray
// schedule read (motion vectors, reactive mask) and for the other G-buffer images: stated wrong, every pass refuses
// them by field name before it records anything; stated right, they are accepted.
#include <catch2/catch_test_macros.hpp>

#include <functional>
#include <string>
#include <vector>

#include "pass_constants.h"
#include "synthetic_gbuffer.h"
#include "vulkan_formats.h"

using namespace rbtest;

namespace {

constexpr uint32_t kW = 16, kH = 12;

struct Case {
  const char* field;   // what the message must name
  const char* remedy;  // and what it must tell the engine to do
  std::function<void(rb::GBufferDesc&)> damage;
};

// A primary command buffer that was never begun: recording anything into it is a validation error, so a pass that
// refuses its input before touching the GPU leaves the validation layer silent.
class NeverBegunCommandBuffer {
 public:
  explicit NeverBegunCommandBuffer(rb::HeadlessDevice& dev) : dev_(dev) {
    auto createPool = reinterpret_cast<PFN_vkCreateCommandPool>(dev.deviceProc("vkCreateCommandPool"));
    auto allocate = reinterpret_cast<PFN_vkAllocateCommandBuffers>(dev.deviceProc("vkAllocateCommandBuffers"));
    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.queueFamilyIndex = dev.queueFamily();
    REQUIRE(createPool(dev.device(), &pci, nullptr, &pool_) == VK_SUCCESS);
    VkCommandBufferAllocateInfo cai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    cai.commandPool = pool_;
    cai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    cai.commandBufferCount = 1;
    REQUIRE(allocate(dev.device(), &cai, &cmd_) == VK_SUCCESS);
  }
  ~NeverBegunCommandBuffer() {
    auto destroyPool = reinterpret_cast<PFN_vkDestroyCommandPool>(dev_.deviceProc("vkDestroyCommandPool"));
    destroyPool(dev_.device(), pool_, nullptr);
  }
  NeverBegunCommandBuffer(const NeverBegunCommandBuffer&) = delete;
  NeverBegunCommandBuffer& operator=(const NeverBegunCommandBuffer&) = delete;
  VkCommandBuffer get() const { return cmd_; }

 private:
  rb::HeadlessDevice& dev_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
};

// Each case's damaged G-buffer is given to AoPass, ShadowPass and Denoiser: each must refuse it with
// InvalidArgument and a message naming the field and the remedy, and record nothing.
void expectRefusedByEveryPass(const std::vector<Case>& cases) {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(kW, kH));
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto shadow = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(shadow);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  NeverBegunCommandBuffer notRecording(fx.device());
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
        for (const Case& c : cases) {
          rb::GBufferDesc gbuffer = g;
          c.damage(gbuffer);
          const VkCommandBuffer cmd = notRecording.get();
          const rb::Status refused[] = {
              ao.value()->record(cmd, {.gbuffer = gbuffer, .tlas = tlas}),
              shadow.value()->record(cmd, {.gbuffer = gbuffer, .tlas = tlas, .light = rb::Light{}}),
              denoiser.value()->record(cmd, {.gbuffer = gbuffer, .signal = g.normal.view})};
          for (const rb::Status& st : refused) {
            REQUIRE_FALSE(st);
            INFO(st.error().message);
            CHECK(st.error().code == rb::ErrorCode::InvalidArgument);
            CHECK(st.error().message.find(c.field) != std::string::npos);
            CHECK(st.error().message.find(c.remedy) != std::string::npos);
          }
        }
      },
      [](const rb::GBufferDesc&) {});
  CHECK(fx.device().validationErrorCount() == 0);  // nothing was recorded into the never-begun command buffer
}

// The stated parts of a G-buffer image, on the view it already has.
std::function<void(rb::GBufferDesc&)> stateReactive(VkFormat format, uint32_t width, uint32_t height) {
  return [=](rb::GBufferDesc& g) {
    g.reactiveMask = {.view = g.normal.view, .format = format, .width = width, .height = height};
  };
}
std::function<void(rb::GBufferDesc&)> stateMotion(VkFormat format, uint32_t width, uint32_t height) {
  return [=](rb::GBufferDesc& g) {
    g.motionVectors = {.view = g.normal.view, .format = format, .width = width, .height = height};
  };
}

// validateGBufferImages alone (no GPU) accepts `format` stated for `field`, on a G-buffer of stand-in views.
bool acceptedFor(rb::GBufferImage rb::GBufferDesc::*field, VkFormat format) {
  rb::GBufferDesc g;
  g.width = kW, g.height = kH;
  const VkImageView standIn = reinterpret_cast<VkImageView>(uintptr_t(0x10));
  g.depth.view = g.normal.view = standIn;
  g.*field = {.view = standIn, .format = format, .width = kW, .height = kH};
  const rb::Status st = rb::validateGBufferImages(g, "test");
  if (!st) UNSCOPED_INFO(st.error().message);
  return bool(st);
}

}  // namespace

TEST_CASE("a reactive mask stated at another size than the G-buffer is refused by name", "[denoise][motion][errors]") {
  const char* remedy = "must be the G-buffer's size";
  expectRefusedByEveryPass({
      {"GBufferDesc::reactiveMask.width x .height 8x6", remedy, stateReactive(VK_FORMAT_R8_UNORM, kW / 2, kH / 2)},
      {"GBufferDesc::reactiveMask.width x .height 17x12", remedy, stateReactive(VK_FORMAT_UNDEFINED, kW + 1, kH)},
      {"GBufferDesc::reactiveMask.width x .height 16x0", remedy, stateReactive(VK_FORMAT_R8_UNORM, kW, 0)},
  });
}

TEST_CASE("a reactive mask stated in an integer, depth or compressed format is refused by name",
          "[denoise][motion][errors]") {
  expectRefusedByEveryPass({
      {"GBufferDesc::reactiveMask.format VK_FORMAT_R8_UINT is an integer format", "UNORM or SFLOAT",
       stateReactive(VK_FORMAT_R8_UINT, kW, kH)},
      {"GBufferDesc::reactiveMask.format VK_FORMAT_R32_SINT is an integer format", "UNORM or SFLOAT",
       stateReactive(VK_FORMAT_R32_SINT, 0, 0)},
      {"GBufferDesc::reactiveMask.format VK_FORMAT_D32_SFLOAT is a depth/stencil format", "colour image",
       stateReactive(VK_FORMAT_D32_SFLOAT, kW, kH)},
      {"GBufferDesc::reactiveMask.format VK_FORMAT_S8_UINT is a depth/stencil format", "colour image",
       stateReactive(VK_FORMAT_S8_UINT, kW, kH)},
      {"GBufferDesc::reactiveMask.format VkFormat 139 (block-compressed)", "VK_FORMAT_R8_UNORM",  // BC4_UNORM
       stateReactive(VK_FORMAT_BC4_UNORM_BLOCK, kW, kH)},
  });
}

TEST_CASE("motion vectors stated in a one-channel or normalized format are refused by name",
          "[denoise][motion][errors]") {
  const char* remedy = "VK_FORMAT_R16G16_SFLOAT";
  expectRefusedByEveryPass({
      {"GBufferDesc::motionVectors.format VK_FORMAT_R16_SFLOAT has one channel", remedy,
       stateMotion(VK_FORMAT_R16_SFLOAT, kW, kH)},
      {"GBufferDesc::motionVectors.format VK_FORMAT_R32_SFLOAT has one channel", remedy,
       stateMotion(VK_FORMAT_R32_SFLOAT, 0, 0)},
      {"GBufferDesc::motionVectors.format VK_FORMAT_R16G16_UNORM is normalized", remedy,
       stateMotion(VK_FORMAT_R16G16_UNORM, kW, kH)},
      {"GBufferDesc::motionVectors.format VK_FORMAT_R16G16_SNORM is normalized", remedy,
       stateMotion(VK_FORMAT_R16G16_SNORM, kW, kH)},
      {"GBufferDesc::motionVectors.format VK_FORMAT_R8G8B8A8_UNORM is normalized", remedy,
       stateMotion(VK_FORMAT_R8G8B8A8_UNORM, kW, kH)},
      {"GBufferDesc::motionVectors.format VK_FORMAT_B10G11R11_UFLOAT_PACK32 has no sign bit", remedy,
       stateMotion(VK_FORMAT_B10G11R11_UFLOAT_PACK32, kW, kH)},
      {"GBufferDesc::motionVectors.format VK_FORMAT_R16G16_SINT is an integer format", "UNORM or SFLOAT",
       stateMotion(VK_FORMAT_R16G16_SINT, kW, kH)},
      {"GBufferDesc::motionVectors.format VK_FORMAT_D32_SFLOAT is a depth/stencil format", "colour image",
       stateMotion(VK_FORMAT_D32_SFLOAT, kW, kH)},
  });
}

TEST_CASE("motion vectors stated at another size than the G-buffer are refused by name", "[denoise][motion][errors]") {
  const char* remedy = "must be the G-buffer's size";
  expectRefusedByEveryPass({
      {"GBufferDesc::motionVectors.width x .height 8x6", remedy, stateMotion(VK_FORMAT_R16G16_SFLOAT, kW / 2, kH / 2)},
      {"GBufferDesc::motionVectors.width x .height 32x24", remedy, stateMotion(VK_FORMAT_UNDEFINED, 2 * kW, 2 * kH)},
      {"GBufferDesc::motionVectors.width x .height 0x12", remedy, stateMotion(VK_FORMAT_R16G16_SFLOAT, 0, kH)},
  });
}

TEST_CASE("the other G-buffer images: a stated depth format for depth, a colour format for the rest",
          "[denoise][motion][errors]") {
  expectRefusedByEveryPass({
      {"GBufferDesc::depth.format VK_FORMAT_R32_SFLOAT is not a depth format", "DEPTH aspect",
       [](rb::GBufferDesc& g) { g.depth.format = VK_FORMAT_R32_SFLOAT; }},
      {"GBufferDesc::depth.format VK_FORMAT_D16_UNORM differs from GBufferDesc::depthFormat", "set depthFormat",
       [](rb::GBufferDesc& g) { g.depth.format = VK_FORMAT_D16_UNORM; }},
      {"GBufferDesc::normal.format VK_FORMAT_D32_SFLOAT is a depth/stencil format", "colour image",
       [](rb::GBufferDesc& g) { g.normal.format = VK_FORMAT_D32_SFLOAT; }},
      {"GBufferDesc::normal.width x .height 8x12", "must be the G-buffer's size",
       [](rb::GBufferDesc& g) { g.normal.width = kW / 2, g.normal.height = kH; }},
      {"GBufferDesc::depth.width x .height 16x13", "must be the G-buffer's size",
       [](rb::GBufferDesc& g) { g.depth.width = kW, g.depth.height = kH + 1; }},
  });
}

TEST_CASE("motion inputs stated in a suitable format at the G-buffer's size are accepted",
          "[denoise][motion][errors]") {
  // Every format gbuffer.h names as suitable passes the one validator...
  for (VkFormat f : {VK_FORMAT_R16G16_SFLOAT, VK_FORMAT_R32G32_SFLOAT, VK_FORMAT_R16G16B16A16_SFLOAT,
                     VK_FORMAT_R32G32B32A32_SFLOAT, VK_FORMAT_R16G16B16_SFLOAT}) {
    INFO(rb::formatName(f));
    CHECK(acceptedFor(&rb::GBufferDesc::motionVectors, f));
  }
  for (VkFormat f :
       {VK_FORMAT_R8_UNORM, VK_FORMAT_R8G8_UNORM, VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_UNORM,
        VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_R16_SFLOAT, VK_FORMAT_R16_UNORM, VK_FORMAT_R32_SFLOAT,
        VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_A2B10G10R10_UNORM_PACK32, VK_FORMAT_B10G11R11_UFLOAT_PACK32}) {
    INFO(rb::formatName(f));
    CHECK(acceptedFor(&rb::GBufferDesc::reactiveMask, f));
  }
  for (VkFormat f : {VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_R16G16_SNORM, VK_FORMAT_R16G16B16A16_SFLOAT,
                     VK_FORMAT_A2B10G10R10_UNORM_PACK32}) {
    INFO(rb::formatName(f));
    CHECK(acceptedFor(&rb::GBufferDesc::geometricNormal, f));
    CHECK(acceptedFor(&rb::GBufferDesc::albedo, f));
  }
  // ... and the names in the messages are the Vulkan ones.
  CHECK(rb::formatName(VK_FORMAT_R8_UINT) == "VK_FORMAT_R8_UINT");
  CHECK(rb::formatName(VK_FORMAT_A8B8G8R8_SRGB_PACK32) == "VK_FORMAT_A8B8G8R8_SRGB_PACK32");
  CHECK(rb::formatName(VK_FORMAT_A2R10G10B10_SINT_PACK32) == "VK_FORMAT_A2R10G10B10_SINT_PACK32");
  CHECK(rb::formatName(VK_FORMAT_R64G64B64A64_SFLOAT) == "VK_FORMAT_R64G64B64A64_SFLOAT");
  CHECK(rb::formatName(VK_FORMAT_D24_UNORM_S8_UINT) == "VK_FORMAT_D24_UNORM_S8_UINT");
  CHECK(rb::formatName(VK_FORMAT_G8B8G8R8_422_UNORM) == "VkFormat 1000156000");

  // On the GPU: real images in the stated formats, every pass records.
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(kW, kH));
  const std::vector<uint16_t> still(size_t(kW) * kH * 2, 0);  // RG16F zero motion
  const std::vector<uint8_t> calm(size_t(kW) * kH, 0);        // R8 unorm, nothing reactive
  SampledImage motion = uploadSampledImage(fx, VK_FORMAT_R16G16_SFLOAT, VK_IMAGE_ASPECT_COLOR_BIT, kW, kH, still.data(),
                                           still.size() * sizeof(uint16_t));
  SampledImage mask = uploadSampledImage(fx, VK_FORMAT_R8_UNORM, VK_IMAGE_ASPECT_COLOR_BIT, kW, kH, calm.data(),
                                         calm.size());
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto shadow = rb::ShadowPass::create(fx.ctx());
  RB_REQUIRE_OK(shadow);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& g, const rb::TlasInfo& tlas) {
        rb::GBufferDesc gbuffer = g;
        // The synthetic G-buffer's own images: D32 depth, RGBA32F normals.
        gbuffer.depth.format = VK_FORMAT_D32_SFLOAT, gbuffer.depth.width = kW, gbuffer.depth.height = kH;
        gbuffer.normal.format = VK_FORMAT_R32G32B32A32_SFLOAT, gbuffer.normal.width = kW, gbuffer.normal.height = kH;
        gbuffer.motionVectors = {.view = motion.view, .format = VK_FORMAT_R16G16_SFLOAT, .width = kW, .height = kH};
        gbuffer.reactiveMask = {.view = mask.view, .format = VK_FORMAT_R8_UNORM, .width = kW, .height = kH};
        RB_REQUIRE_OK(ao.value()->record(cmd, {.gbuffer = gbuffer, .tlas = tlas}));
        RB_REQUIRE_OK(shadow.value()->record(cmd, {.gbuffer = gbuffer, .tlas = tlas, .light = rb::Light{}}));
        RB_REQUIRE_OK(denoiser.value()->record(cmd, {.gbuffer = gbuffer, .signal = ao.value()->outputs().aoView}));
      },
      [](const rb::GBufferDesc&) {});
  destroySampledImage(fx, motion);
  destroySampledImage(fx, mask);
}
