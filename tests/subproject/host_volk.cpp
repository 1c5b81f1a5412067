// A host with its own volk and VK_NO_PROTOTYPES on its target (volk's other way), Raybridge's headers first.
#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <volk.h>

#include <cstdio>

int main() {
  if (volkInitialize() != VK_SUCCESS) return 1;
  auto device = rb::HeadlessDevice::create();
  if (!device) {
    std::fprintf(stderr, "host_volk: %s\n", device.what());
    return 1;
  }
  volkLoadInstanceOnly(device.value()->instance());
  volkLoadDevice(device.value()->device());
  rb::ContextDesc desc = device.value()->contextDesc();
  desc.getInstanceProcAddr = vkGetInstanceProcAddr;  // volk's pointer
  auto ctx = rb::Context::create(desc);
  if (!ctx) {
    std::fprintf(stderr, "host_volk: %s\n", ctx.what());
    return 1;
  }
  if (vkDeviceWaitIdle(device.value()->device()) != VK_SUCCESS) return 1;
  ctx.value().reset();
  std::printf("host_volk: context created; vkDeviceWaitIdle through volk\n");
  return 0;
}
