// Presentation: the frame is rendered offscreen as usual and blitted into the acquired swapchain image; the
// overlay hook draws onto the tonemapped image first.
#include <algorithm>

#include "engine_impl.h"
#include "vk_check.h"

namespace sample_engine {

using namespace detail;

std::string Engine::Impl::createSwapchain(uint32_t width, uint32_t height) {
  vkDeviceWaitIdle(ctx.device);
  VkSurfaceCapabilitiesKHR caps;
  SE_VK_TRY(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(ctx.physicalDevice, swapchain.surface, &caps));
  if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT)) return "swapchain images cannot be blit targets";
  VkExtent2D extent = caps.currentExtent;
  if (extent.width == UINT32_MAX) {
    extent.width = std::clamp(width, caps.minImageExtent.width, caps.maxImageExtent.width);
    extent.height = std::clamp(height, caps.minImageExtent.height, caps.maxImageExtent.height);
  }
  if (extent.width == 0 || extent.height == 0) return {};  // minimized: keep the old swapchain

  uint32_t n = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(ctx.physicalDevice, swapchain.surface, &n, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(n);
  vkGetPhysicalDeviceSurfaceFormatsKHR(ctx.physicalDevice, swapchain.surface, &n, formats.data());
  if (formats.empty()) return "surface reports no formats";
  VkSurfaceFormatKHR format = formats[0];
  for (const auto& f : formats)
    if ((f.format == VK_FORMAT_B8G8R8A8_SRGB || f.format == VK_FORMAT_R8G8B8A8_SRGB) &&
        f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) {
      format = f;
      break;
    }

  VkSwapchainKHR old = swapchain.swapchain;
  VkSwapchainCreateInfoKHR ci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  ci.surface = swapchain.surface;
  ci.minImageCount = caps.maxImageCount ? std::min(caps.minImageCount + 1, caps.maxImageCount) : caps.minImageCount + 1;
  ci.imageFormat = format.format;
  ci.imageColorSpace = format.colorSpace;
  ci.imageExtent = extent;
  ci.imageArrayLayers = 1;
  ci.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.preTransform = caps.currentTransform;
  ci.compositeAlpha = (caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR)
                          ? VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR
                          : VkCompositeAlphaFlagBitsKHR(caps.supportedCompositeAlpha & -caps.supportedCompositeAlpha);
  ci.presentMode = VK_PRESENT_MODE_FIFO_KHR;  // always available
  ci.clipped = VK_TRUE;
  ci.oldSwapchain = old;
  VkSwapchainKHR created = VK_NULL_HANDLE;
  SE_VK_TRY(vkCreateSwapchainKHR(ctx.device, &ci, nullptr, &created));
  destroySwapchain(false);
  swapchain.swapchain = created;
  swapchain.format = format.format;
  swapchain.extent = extent;
  vkGetSwapchainImagesKHR(ctx.device, created, &n, nullptr);
  swapchain.images.resize(n);
  vkGetSwapchainImagesKHR(ctx.device, created, &n, swapchain.images.data());
  swapchain.renderFinished.resize(n);
  for (VkSemaphore& s : swapchain.renderFinished) {
    VkSemaphoreCreateInfo sci{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    SE_VK_TRY(vkCreateSemaphore(ctx.device, &sci, nullptr, &s));
  }
  return createTargets(extent);
}

void Engine::Impl::destroySwapchain(bool destroySurface) {
  for (VkSemaphore s : swapchain.renderFinished) vkDestroySemaphore(ctx.device, s, nullptr);
  swapchain.renderFinished.clear();
  swapchain.images.clear();
  if (swapchain.swapchain) vkDestroySwapchainKHR(ctx.device, swapchain.swapchain, nullptr);
  swapchain.swapchain = VK_NULL_HANDLE;
  if (destroySurface && swapchain.surface) {
    vkDestroySurfaceKHR(ctx.instance, swapchain.surface, nullptr);
    swapchain.surface = VK_NULL_HANDLE;
  }
}

// ---------------------------------------------------------------------------------------------------------
// Overlay hook

void Engine::setOverlayHook(OverlayHook hook) { impl_->overlayHook = std::move(hook); }

std::string Engine::Impl::prepareOverlay() {
  if (!overlayHook) return {};
  if (!overlayRenderPass) {
    VkAttachmentDescription color{};
    color.format = kLdrFormat;
    color.samples = VK_SAMPLE_COUNT_1_BIT;
    color.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
    color.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    color.stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    color.stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    color.initialLayout = color.finalLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
    VkAttachmentReference ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 1;
    subpass.pColorAttachments = &ref;
    VkRenderPassCreateInfo ci{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    ci.attachmentCount = 1;
    ci.pAttachments = &color;
    ci.subpassCount = 1;
    ci.pSubpasses = &subpass;
    SE_VK_TRY(vkCreateRenderPass(ctx.device, &ci, nullptr, &overlayRenderPass));
  }
  if (!overlayFramebuffer) {  // destroyed with the targets it shows
    VkFramebufferCreateInfo ci{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    ci.renderPass = overlayRenderPass;
    ci.attachmentCount = 1;
    ci.pAttachments = &targets.ldr.view;
    ci.width = targets.extent.width;
    ci.height = targets.extent.height;
    ci.layers = 1;
    SE_VK_TRY(vkCreateFramebuffer(ctx.device, &ci, nullptr, &overlayFramebuffer));
  }
  return {};
}

// The tonemap pass left targets.ldr in TRANSFER_SRC_OPTIMAL; the hook gets it as a colour attachment and the
// blit / readback get it back in TRANSFER_SRC_OPTIMAL.
void Engine::Impl::recordOverlay(FrameResources& frame, std::optional<uint32_t> swapchainImage) {
  VkCommandBuffer cmd = frame.cmd;
  imageBarrier(cmd, targets.ldr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
               VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
               VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
               VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
               VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT | VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT);
  OverlayHookInfo info;
  info.commandBuffer = cmd;
  info.frameIndex = uint32_t(&frame - frames.data());
  info.frameNumber = frame.frameNumber;
  info.target = {targets.ldr.image, targets.ldr.view, kLdrFormat, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
  info.extent = targets.extent;
  info.renderPass = overlayRenderPass;
  info.framebuffer = overlayFramebuffer;
  info.swapchainImageCount = swapchainImage ? uint32_t(swapchain.images.size()) : 0u;
  info.instance = ctx.instance;
  info.physicalDevice = ctx.physicalDevice;
  info.device = ctx.device;
  info.queue = ctx.queue;
  info.queueFamily = ctx.queueFamily;
  info.getInstanceProcAddr = &vkGetInstanceProcAddr;
  info.apiVersion = VK_API_VERSION_1_3;
  overlayHook(info);
  imageBarrier(cmd, targets.ldr.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
               VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
               VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
               VK_ACCESS_2_TRANSFER_READ_BIT);
}

void Engine::Impl::destroyOverlayFramebuffer() {
  if (overlayFramebuffer) vkDestroyFramebuffer(ctx.device, overlayFramebuffer, nullptr);
  overlayFramebuffer = VK_NULL_HANDLE;
}

void Engine::Impl::destroyOverlay() {
  destroyOverlayFramebuffer();
  if (overlayRenderPass) vkDestroyRenderPass(ctx.device, overlayRenderPass, nullptr);
  overlayRenderPass = VK_NULL_HANDLE;
}

Status Engine::attachSurface(VkSurfaceKHR surface, uint32_t width, uint32_t height) {
  if (!impl_->ctx.swapchainEnabled) return Status::failure("attachSurface: EngineConfig::enableSwapchain was false");
  VkBool32 supported = VK_FALSE;
  vkGetPhysicalDeviceSurfaceSupportKHR(impl_->ctx.physicalDevice, impl_->ctx.queueFamily, surface, &supported);
  if (!supported) return Status::failure("attachSurface: the engine's queue cannot present to this surface");
  impl_->destroySwapchain(true);
  impl_->swapchain.surface = surface;
  std::string e = impl_->createSwapchain(width, height);
  return e.empty() ? Status::success() : Status::failure("swapchain: " + e);
}

Status Engine::resizeSwapchain(uint32_t width, uint32_t height) {
  if (!impl_->swapchain.surface) return Status::failure("resizeSwapchain: no surface attached");
  std::string e = impl_->createSwapchain(width, height);
  return e.empty() ? Status::success() : Status::failure("swapchain: " + e);
}

}  // namespace sample_engine
