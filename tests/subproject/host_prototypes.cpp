// A host on the loader's prototypes: Raybridge's headers first, then vulkan.h, and the host's own
// vkDeviceWaitIdle from the loader. Built from the sources (add_subdirectory), nothing of Raybridge's build
// settings may take its prototypes away.
#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <vulkan/vulkan.h>

#include <cstdio>

int main() {
  auto device = rb::HeadlessDevice::create();
  if (!device) {
    std::fprintf(stderr, "host_prototypes: %s\n", device.what());
    return 1;
  }
  rb::ContextDesc desc = device.value()->contextDesc();
  desc.getInstanceProcAddr = vkGetInstanceProcAddr;  // the loader's own, as linked
  auto ctx = rb::Context::create(desc);
  if (!ctx) {
    std::fprintf(stderr, "host_prototypes: %s\n", ctx.what());
    return 1;
  }
  if (vkDeviceWaitIdle(device.value()->device()) != VK_SUCCESS) return 1;
  ctx.value().reset();
  std::printf("host_prototypes: context created; vkDeviceWaitIdle through the loader's prototype\n");
  return 0;
}
