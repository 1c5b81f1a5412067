// An engine that calls Vulkan through the loader's prototypes (vulkan.h without VK_NO_PROTOTYPES) includes
// Raybridge, hands it the loader's own vkGetInstanceProcAddr, and keeps calling the prototypes itself.
#include <vulkan/vulkan.h>

#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <cstdio>

int main() {
  auto device = rb::HeadlessDevice::create();
  if (!device) {
    std::fprintf(stderr, "consumer_prototypes: %s\n", device.what());
    return 1;
  }
  rb::HeadlessDevice& d = *device.value();
  // The engine's own calls, through the prototypes the loader exports.
  VkPhysicalDeviceProperties properties;
  vkGetPhysicalDeviceProperties(d.physicalDevice(), &properties);
  const rb::ContextDesc desc{.instance = d.instance(),
                             .physicalDevice = d.physicalDevice(),
                             .device = d.device(),
                             .getInstanceProcAddr = vkGetInstanceProcAddr,  // the loader's, as linked
                             .framesInFlight = 2,
                             .mainQueueFamily = d.queueFamily(),
                             .apiVersion = VK_API_VERSION_1_3};
  auto ctx = rb::Context::create(desc);
  if (!ctx) {
    std::fprintf(stderr, "consumer_prototypes: %s\n", ctx.what());
    return 1;
  }
  auto pass = rb::AoPass::create(*ctx.value());
  if (!pass) {
    std::fprintf(stderr, "consumer_prototypes: %s\n", pass.what());
    return 1;
  }
  if (vkDeviceWaitIdle(d.device()) != VK_SUCCESS) return 1;
  pass.value().reset();
  ctx.value().reset();
  std::printf("consumer_prototypes: AO pass created on %s through the loader's prototypes\n", properties.deviceName);
  return 0;
}
