// Dear ImGui on the engine's overlay hook: see viewer_overlay.h.
#include "viewer_overlay.h"

#include <cmath>
#include <cstring>

#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_vulkan.h>

namespace se = sample_engine;

namespace rbViewer {

namespace {

// ImGui's colours are sRGB values; the engine's target is an sRGB image that blends in linear space, so the
// style's colours are linearised once to look as ImGui means them.
float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

void linearizeStyle(ImGuiStyle& style) {
  for (ImVec4& c : style.Colors) {
    c.x = srgbToLinear(c.x);
    c.y = srgbToLinear(c.y);
    c.z = srgbToLinear(c.z);
  }
}

// Only ImGui's ImGui_ImplVulkanH_* window helpers (never called here) use these; the loader may not give them
// out without the surface extensions, and ImGui_ImplVulkan_LoadFunctions refuses a null entry.
void unusedSwapchainFunction() {}

}  // namespace

struct ImGuiOverlay::Impl {
  GLFWwindow* window = nullptr;
  bool glfwBackend = false;
  bool vulkanBackend = false;
  bool uiReady = false;          // endFrame() since the last recorded frame
  uint64_t fontUploadFrame = 0;  // frame whose command buffer uploaded the fonts; 0 = none pending
  std::string error;

  // What the first hook call brought, and the few functions the overlay calls itself.
  VkInstance instance = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  PFN_vkGetInstanceProcAddr getInstanceProcAddr = nullptr;
  PFN_vkGetDeviceProcAddr getDeviceProcAddr = nullptr;
  PFN_vkCreateDescriptorPool createDescriptorPool = nullptr;
  PFN_vkDestroyDescriptorPool destroyDescriptorPool = nullptr;
  PFN_vkCmdBeginRenderPass cmdBeginRenderPass = nullptr;
  PFN_vkCmdEndRenderPass cmdEndRenderPass = nullptr;
  VkDescriptorPool descriptorPool = VK_NULL_HANDLE;

  static PFN_vkVoidFunction load(const char* name, void* user) {
    const Impl& self = *static_cast<const Impl*>(user);
    PFN_vkVoidFunction f = self.getDeviceProcAddr(self.device, name);
    if (!f) f = self.getInstanceProcAddr(self.instance, name);
    if (!f && std::strstr(name, "KHR")) f = reinterpret_cast<PFN_vkVoidFunction>(&unusedSwapchainFunction);
    return f;
  }

  bool startVulkan(const se::OverlayHookInfo& info);
  void record(const se::OverlayHookInfo& info);
};

bool ImGuiOverlay::Impl::startVulkan(const se::OverlayHookInfo& info) {
  instance = info.instance;
  device = info.device;
  getInstanceProcAddr = info.getInstanceProcAddr;
  getDeviceProcAddr = reinterpret_cast<PFN_vkGetDeviceProcAddr>(getInstanceProcAddr(instance, "vkGetDeviceProcAddr"));
  if (!getDeviceProcAddr) return error = "vkGetDeviceProcAddr not found", false;
  createDescriptorPool = reinterpret_cast<PFN_vkCreateDescriptorPool>(
      getDeviceProcAddr(device, "vkCreateDescriptorPool"));
  destroyDescriptorPool = reinterpret_cast<PFN_vkDestroyDescriptorPool>(
      getDeviceProcAddr(device, "vkDestroyDescriptorPool"));
  cmdBeginRenderPass = reinterpret_cast<PFN_vkCmdBeginRenderPass>(getDeviceProcAddr(device, "vkCmdBeginRenderPass"));
  cmdEndRenderPass = reinterpret_cast<PFN_vkCmdEndRenderPass>(getDeviceProcAddr(device, "vkCmdEndRenderPass"));
  if (!createDescriptorPool || !destroyDescriptorPool || !cmdBeginRenderPass || !cmdEndRenderPass)
    return error = "the device lacks a core Vulkan 1.0 function", false;
  if (!ImGui_ImplVulkan_LoadFunctions(&Impl::load, this))
    return error = "ImGui_ImplVulkan_LoadFunctions: a Vulkan function was not found", false;

  // ImGui 1.86's renderer allocates one descriptor set (the font atlas).
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1};
  VkDescriptorPoolCreateInfo pci{};
  pci.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO;
  pci.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
  pci.maxSets = 1;
  pci.poolSizeCount = 1;
  pci.pPoolSizes = &size;
  if (VkResult r = createDescriptorPool(device, &pci, nullptr, &descriptorPool); r != VK_SUCCESS)
    return error = "vkCreateDescriptorPool failed (VkResult " + std::to_string(int(r)) + ")", false;

  ImGui_ImplVulkan_InitInfo init{};
  init.Instance = info.instance;
  init.PhysicalDevice = info.physicalDevice;
  init.Device = info.device;
  init.QueueFamily = info.queueFamily;
  init.Queue = info.queue;  // only for ImGui's own font upload helper, which the overlay does not use
  init.DescriptorPool = descriptorPool;
  init.Subpass = 0;
  // ImGui ring-buffers its vertex and index buffers over ImageCount draws: one per frame in flight.
  init.MinImageCount = info.framesInFlight < 2 ? 2 : info.framesInFlight;
  init.ImageCount = init.MinImageCount;
  init.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
  if (!ImGui_ImplVulkan_Init(&init, info.renderPass)) return error = "ImGui_ImplVulkan_Init failed", false;
  vulkanBackend = true;
  if (!ImGui_ImplVulkan_CreateFontsTexture(info.commandBuffer))
    return error = "ImGui_ImplVulkan_CreateFontsTexture failed", false;
  fontUploadFrame = info.frameNumber;
  return true;
}

void ImGuiOverlay::Impl::record(const se::OverlayHookInfo& info) {
  if (!error.empty()) return;
  if (!vulkanBackend && !startVulkan(info)) return;
  if (fontUploadFrame && info.frameNumber >= fontUploadFrame + info.framesInFlight) {
    ImGui_ImplVulkan_DestroyFontUploadObjects();  // that frame has finished on the GPU
    fontUploadFrame = 0;
  }
  if (!uiReady) return;
  uiReady = false;
  ImDrawData* draw = ImGui::GetDrawData();
  // During a resize the UI may have been laid out for the other size for one frame: skip it.
  if (!draw || uint32_t(draw->DisplaySize.x * draw->FramebufferScale.x) != info.extent.width ||
      uint32_t(draw->DisplaySize.y * draw->FramebufferScale.y) != info.extent.height)
    return;
  VkRenderPassBeginInfo rbi{};
  rbi.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
  rbi.renderPass = info.renderPass;
  rbi.framebuffer = info.framebuffer;
  rbi.renderArea = {{0, 0}, info.extent};
  cmdBeginRenderPass(info.commandBuffer, &rbi, VK_SUBPASS_CONTENTS_INLINE);
  ImGui_ImplVulkan_RenderDrawData(draw, info.commandBuffer);
  cmdEndRenderPass(info.commandBuffer);
}

se::Result<std::unique_ptr<ImGuiOverlay>> ImGuiOverlay::create(GLFWwindow* window) {
  using R = se::Result<std::unique_ptr<ImGuiOverlay>>;
  if (!window) return R::failure("ImGuiOverlay: no window");
  if (ImGui::GetCurrentContext()) return R::failure("ImGuiOverlay: an ImGui context exists already (one per process)");
  IMGUI_CHECKVERSION();
  auto impl = std::make_unique<Impl>();
  impl->window = window;
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // no imgui.ini in the working directory
  ImGui::StyleColorsDark();
  linearizeStyle(ImGui::GetStyle());
  // NewFrame() wants a built atlas; the Vulkan backend uploads these texels on the first hook call.
  unsigned char* pixels = nullptr;
  int w = 0, h = 0;
  io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);
  if (!ImGui_ImplGlfw_InitForVulkan(window, true)) {
    ImGui::DestroyContext();
    return R::failure("ImGui_ImplGlfw_InitForVulkan failed");
  }
  impl->glfwBackend = true;
  return R::success(std::unique_ptr<ImGuiOverlay>(new ImGuiOverlay(std::move(impl))));
}

ImGuiOverlay::ImGuiOverlay(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

ImGuiOverlay::~ImGuiOverlay() {
  if (impl_->vulkanBackend) ImGui_ImplVulkan_Shutdown();  // also frees a pending font upload buffer
  if (impl_->descriptorPool) impl_->destroyDescriptorPool(impl_->device, impl_->descriptorPool, nullptr);
  if (impl_->glfwBackend) ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
}

void ImGuiOverlay::beginFrame() {
  if (impl_->vulkanBackend) ImGui_ImplVulkan_NewFrame();  // it starts on the first hook call
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
}

void ImGuiOverlay::endFrame() {
  ImGui::Render();
  impl_->uiReady = true;
}

se::OverlayHook ImGuiOverlay::hook() {
  return [impl = impl_.get()](const se::OverlayHookInfo& info) { impl->record(info); };
}

bool ImGuiOverlay::wantsMouse() const { return ImGui::GetIO().WantCaptureMouse; }
bool ImGuiOverlay::wantsKeyboard() const { return ImGui::GetIO().WantCaptureKeyboard; }
const std::string& ImGuiOverlay::lastError() const { return impl_->error; }

}  // namespace rbViewer
