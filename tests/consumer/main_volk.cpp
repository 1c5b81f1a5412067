// An engine with its own volk: volk.h first (it declares every Vulkan function as its own pointer), then
// Raybridge, whose library must define and call none of them.
#include <volk.h>

#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <cstdio>

int main() {
  if (volkInitialize() != VK_SUCCESS) {
    std::fprintf(stderr, "consumer_volk: no Vulkan loader\n");
    return 1;
  }
  auto device = rb::HeadlessDevice::create();
  if (!device) {
    std::fprintf(stderr, "consumer_volk: %s\n", device.what());
    return 1;
  }
  rb::HeadlessDevice& d = *device.value();
  volkLoadInstanceOnly(d.instance());
  volkLoadDevice(d.device());
  auto ctx = rb::Context::create({.instance = d.instance(),
                                  .physicalDevice = d.physicalDevice(),
                                  .device = d.device(),
                                  .getInstanceProcAddr = vkGetInstanceProcAddr,  // volk's pointer
                                  .mainQueueFamily = d.queueFamily(),
                                  .apiVersion = VK_API_VERSION_1_3});
  if (!ctx) {
    std::fprintf(stderr, "consumer_volk: %s\n", ctx.what());
    return 1;
  }
  auto pass = rb::ShadowPass::create(*ctx.value());
  if (!pass) {
    std::fprintf(stderr, "consumer_volk: %s\n", pass.what());
    return 1;
  }
  if (vkDeviceWaitIdle(d.device()) != VK_SUCCESS) return 1;  // volk's pointer, loaded for this device
  pass.value().reset();
  ctx.value().reset();
  std::printf("consumer_volk: shadow pass created through volk\n");
  return 0;
}
