// Builds against Raybridge added with add_subdirectory, creates a headless device, a context and the primary
// ray pass (its pipeline is made from the embedded SPIR-V). The unused variable is deliberate: the host
// compiles with warnings on and no -Werror, so the build must still succeed if Raybridge leaks none.
#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <cstdio>

int main() {
  int deliberately_unused_by_the_subproject_test = 0;
  auto device = rb::HeadlessDevice::create();
  if (!device) {
    std::fprintf(stderr, "host: %s\n", device.error().message.c_str());
    return 1;
  }
  auto ctx = rb::Context::create(device.value()->contextDesc());
  if (!ctx) {
    std::fprintf(stderr, "host: %s\n", ctx.error().message.c_str());
    return 1;
  }
  auto pass = rb::PrimaryRayPass::create(*ctx.value());
  if (!pass) {
    std::fprintf(stderr, "host: %s\n", pass.error().message.c_str());
    return 1;
  }
  pass.value().reset();
  ctx.value().reset();
  std::printf("host: primary ray pass created on %s\n", device.value()->deviceName().c_str());
  return 0;
}
