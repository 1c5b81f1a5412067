// Links against the installed SDK, creates a headless device and a context, and builds one BLAS.
#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <cstdio>

int main() {
  auto device = rb::HeadlessDevice::create();
  if (!device) {
    std::fprintf(stderr, "consumer: %s\n", device.error().message.c_str());
    return 1;
  }
  auto ctx = rb::Context::create(device.value()->contextDesc());
  if (!ctx) {
    std::fprintf(stderr, "consumer: %s\n", ctx.error().message.c_str());
    return 1;
  }
  auto service = rb::AccelerationStructureService::create(*ctx.value());
  if (!service) return 1;
  const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t indices[3] = {0, 1, 2};
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                   VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR;
  auto vb = device.value()->createBuffer(sizeof positions, usage, true, positions);
  auto ib = device.value()->createBuffer(sizeof indices, usage, true, indices);
  if (!vb || !ib) return 1;
  rb::MeshDesc mesh;
  mesh.vertexAddress = vb->address;
  mesh.vertexBufferBytes = sizeof positions;
  mesh.vertexCount = 3;
  mesh.indexAddress = ib->address;
  mesh.indexBufferBytes = sizeof indices;
  mesh.triangleCount = 1;
  auto handle = service.value()->registerMesh(mesh);
  if (!handle) {
    std::fprintf(stderr, "consumer: %s\n", handle.error().message.c_str());
    return 1;
  }
  auto cmd = device.value()->beginCommands();
  if (!cmd || !service.value()->recordPendingWork(cmd.value()) || !device.value()->submitAndWait(cmd.value())) {
    return 1;
  }
  bool built = service.value()->isBuilt(handle.value()).value();
  service.value().reset();
  ctx.value().reset();
  device.value()->destroyBuffer(vb.value());
  device.value()->destroyBuffer(ib.value());
  std::printf("consumer: built=%d on %s\n", built ? 1 : 0, device.value()->deviceName().c_str());
  return built ? 0 : 1;
}
