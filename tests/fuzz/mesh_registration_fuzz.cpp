// libFuzzer target: mesh registration in the acceleration-structure service, down to the point where GPU work
// would be recorded: registerMesh (validation against the device, the content hash of the host copies, the build
// size query, dedup and budget bookkeeping), releaseMesh, updateMesh of dynamic meshes, and the queries, in any
// order on handles live, released or forged. recordPendingWork / recordTlasBuild (which record) are never called.
//
// Why a real device: validateMesh() asks the device which vertex formats it can build from and registerMesh()
// queries build sizes, so fuzzing the validation and hashing functions alone would stub exactly the calls where
// bad input meets the driver. One headless device (lavapipe here, with the validation layer when it is installed:
// a validation error is a finding too) is created once in LLVMFuzzerInitialize; a registration costs a few driver
// queries, so the target still runs thousands of inputs a second.
//
// Input (FuzzedDataProvider): which of three services (default; a small BLAS budget; dynamic meshes one frame
// late), then up to 32 operations, each a kind followed by its fields: counts, strides and formats (known, unknown
// and raw enum values), index types and roles (including values past the enums), addresses (zero, unaligned),
// declared buffer sizes (exact or arbitrary), content keys (few, so that dedup hits), host copies of the vertices
// and indices (their bytes from the input, so NaNs and out-of-range indices appear; sized exactly as the header's
// contract says, so ASan catches any read past them; sometimes at an unaligned address) and debug names.
// Invariants checked after every input (a breach aborts, like a crash): live handles counted by stats(), nothing
// built, and once every handle is released no BLAS left.
#include <fuzzer/FuzzedDataProvider.h>

#include <raybridge/headless_device.h>
#include <raybridge/raybridge.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace {

struct Fixture {
  std::unique_ptr<rb::HeadlessDevice> device;
  std::unique_ptr<rb::Context> context;
  std::unique_ptr<rb::AccelerationStructureService> services[3];
  uint32_t validationErrors = 0;
};
Fixture* gFixture = nullptr;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "mesh_registration_fuzz: %s\n", what.c_str());
  std::abort();
}

// A registration and the host copies it was given (kept until released, as an engine would).
struct Live {
  rb::MeshHandle handle;
  std::vector<uint8_t> vertices, indices;
};

constexpr VkFormat kFormats[] = {VK_FORMAT_UNDEFINED,           VK_FORMAT_R32G32B32_SFLOAT,
                                 VK_FORMAT_R32G32_SFLOAT,       VK_FORMAT_R32G32B32A32_SFLOAT,
                                 VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_R16G16_SFLOAT,
                                 VK_FORMAT_R16G16B16A16_SNORM,  VK_FORMAT_R16G16_SNORM,
                                 VK_FORMAT_R8G8B8A8_SNORM,      VK_FORMAT_R8G8B8A8_UNORM,
                                 VK_FORMAT_D32_SFLOAT,          VK_FORMAT_R64G64B64_SFLOAT};

uint32_t formatBytes(VkFormat f) {
  switch (f) {
    case VK_FORMAT_UNDEFINED:
    case VK_FORMAT_R32G32B32_SFLOAT: return 12;
    case VK_FORMAT_R32G32_SFLOAT: return 8;
    case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
    case VK_FORMAT_R16G16B16A16_SFLOAT:
    case VK_FORMAT_R16G16B16A16_SNORM: return 8;
    default: return 4;
  }
}

uint32_t count(FuzzedDataProvider& in) {
  static constexpr uint32_t kEdges[] = {0, 1, 2, 3, 0xFFFF, 0x10000, 0x55555555, 0x55555556, 0x7FFFFFFF, 0xFFFFFFFF};
  switch (in.ConsumeIntegralInRange(0, 3)) {
    case 0: return in.PickValueInArray(kEdges);
    case 1: return in.ConsumeIntegral<uint32_t>();
    default: return in.ConsumeIntegralInRange<uint32_t>(0, 96);
  }
}

VkDeviceAddress address(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange(0, 3)) {
    case 0: return 0;
    case 1: return in.ConsumeIntegral<uint64_t>();
    default: return (uint64_t(in.ConsumeIntegralInRange<uint32_t>(1, 1u << 20)) << 8) + in.ConsumeIntegralInRange(0, 3);
  }
}

// Host bytes: `size` of them (exactly what the contract says the SDK may read) from the input, repeated when the
// input runs short; sometimes one byte past a 16-byte boundary, for a pointer that is not 4-byte aligned.
const void* hostCopy(FuzzedDataProvider& in, uint64_t size, std::vector<uint8_t>& storage) {
  if (size == 0 || size > (1u << 20) || !in.ConsumeBool()) return nullptr;
  const bool unaligned = in.ConsumeIntegralInRange(0, 7) == 0;
  storage.assign(size_t(size) + (unaligned ? 1 : 0), 0);
  uint8_t* dst = storage.data() + (unaligned ? 1 : 0);
  const std::vector<uint8_t> pattern = in.ConsumeBytes<uint8_t>(in.ConsumeIntegralInRange<size_t>(0, 256));
  for (size_t i = 0; i < size && !pattern.empty(); ++i) dst[i] = pattern[i % pattern.size()];
  return dst;
}

rb::MeshDesc meshDesc(FuzzedDataProvider& in, Live& live, std::string& name) {
  rb::MeshDesc d;
  // Any value of the enum's range (0..VK_FORMAT_MAX_ENUM; a value outside it would be the engine's undefined
  // behaviour, not the SDK's), most of them no format at all.
  d.vertexFormat = in.ConsumeBool() ? in.PickValueInArray(kFormats)
                                    : VkFormat(in.ConsumeIntegralInRange<int32_t>(0, VK_FORMAT_MAX_ENUM));
  static constexpr uint32_t kStrides[] = {0, 4, 6, 8, 12, 13, 16, 24, 32, 0x80000000u};
  d.vertexStride = in.ConsumeBool() ? in.PickValueInArray(kStrides) : in.ConsumeIntegral<uint32_t>();
  d.vertexCount = count(in);
  d.triangleCount = in.ConsumeBool() ? d.vertexCount / 3 : count(in);
  d.indexType = rb::IndexType(in.ConsumeIntegralInRange<uint8_t>(0, 3));
  d.role = rb::MeshRole(in.ConsumeIntegralInRange<uint8_t>(0, 2));
  d.nonOpaque = in.ConsumeBool();
  d.vertexAddress = address(in);
  d.indexAddress = address(in);
  const uint64_t stride = d.vertexStride ? d.vertexStride : formatBytes(d.vertexFormat);
  const uint64_t vertexBytes = uint64_t(d.vertexCount) * stride;
  const uint64_t indexSize = d.indexType == rb::IndexType::Uint16 ? 2 : 4;
  const uint64_t indexBytes = uint64_t(d.triangleCount) * 3 * indexSize;
  d.vertexBufferBytes = in.ConsumeBool() ? vertexBytes : in.ConsumeIntegral<uint64_t>();
  d.indexBufferBytes = in.ConsumeBool() ? indexBytes : in.ConsumeIntegral<uint64_t>();
  d.contentKey = in.ConsumeBool() ? 0 : in.ConsumeIntegralInRange<uint64_t>(0, 4);
  d.hostVertices = hostCopy(in, vertexBytes, live.vertices);
  d.hostIndices = hostCopy(in, d.indexType == rb::IndexType::None ? 0 : indexBytes, live.indices);
  if (d.hostIndices && d.vertexCount > 0 && in.ConsumeBool()) {
    // Indices in range, so that the mesh can pass validation and reach the hash and the bookkeeping.
    uint8_t* p = const_cast<uint8_t*>(static_cast<const uint8_t*>(d.hostIndices));
    for (uint64_t i = 0; i < indexBytes / indexSize; ++i) {
      uint32_t v = 0;
      std::memcpy(&v, p + i * indexSize, indexSize);
      v %= d.vertexCount;
      std::memcpy(p + i * indexSize, &v, indexSize);
    }
  }
  d.normalAddress = in.ConsumeBool() ? address(in) : 0;
  d.normalStride = in.ConsumeIntegralInRange<uint32_t>(0, 24);
  d.texcoordAddress = in.ConsumeBool() ? address(in) : 0;
  d.texcoordStride = in.ConsumeIntegralInRange<uint32_t>(0, 24);
  if (in.ConsumeBool()) {
    name = in.ConsumeRandomLengthString(24);
    d.debugName = name.c_str();
  }
  return d;
}

// RAYBRIDGE_FUZZ_TRACE=1 prints every operation of an input (to turn a finding into a test).
bool gTrace = false;

void trace(const char* op, const rb::MeshDesc& d) {
  if (!gTrace) return;
  std::fprintf(stderr,
               "%s: vertexFormat %d vertexStride %u vertexCount %u triangleCount %u indexType %d role %d nonOpaque %d "
               "vertexAddress 0x%llx indexAddress 0x%llx vertexBufferBytes %llu indexBufferBytes %llu contentKey %llu "
               "hostVertices %s hostIndices %s normalAddress 0x%llx normalStride %u texcoordAddress 0x%llx "
               "texcoordStride %u debugName %s%s%s\n",
               op, int(d.vertexFormat), d.vertexStride, d.vertexCount, d.triangleCount, int(d.indexType), int(d.role),
               int(d.nonOpaque), (unsigned long long)d.vertexAddress, (unsigned long long)d.indexAddress,
               (unsigned long long)d.vertexBufferBytes, (unsigned long long)d.indexBufferBytes,
               (unsigned long long)d.contentKey, d.hostVertices ? "set" : "null", d.hostIndices ? "set" : "null",
               (unsigned long long)d.normalAddress, d.normalStride, (unsigned long long)d.texcoordAddress,
               d.texcoordStride, d.debugName ? "'" : "", d.debugName ? d.debugName : "null", d.debugName ? "'" : "");
}

void trace(const char* op, rb::MeshHandle h, const std::string& outcome) {
  if (gTrace) std::fprintf(stderr, "%s {%u, %u}: %s\n", op, h.index, h.generation, outcome.c_str());
}

rb::MeshHandle pickHandle(FuzzedDataProvider& in, const std::vector<Live>& live) {
  if (!live.empty() && in.ConsumeIntegralInRange(0, 3) != 0)
    return live[in.ConsumeIntegralInRange<size_t>(0, live.size() - 1)].handle;
  return rb::MeshHandle{in.ConsumeIntegralInRange<uint32_t>(0, 40), in.ConsumeIntegralInRange<uint32_t>(0, 3)};
}

void checkValidation() {
  rb::HeadlessDevice& device = *gFixture->device;
  const uint32_t errors = device.validationErrorCount();
  if (errors == gFixture->validationErrors) return;
  std::string all;
  for (uint32_t i = gFixture->validationErrors; i < errors; ++i) all += "\n  " + device.validationErrors()[i];
  fail("the validation layer reported errors:" + all);
}

}  // namespace

// The Vulkan driver, loader and validation layer are not ours: what they leak (lavapipe loses one allocation by
// exit) is not a finding of this target.
extern "C" const char* __lsan_default_suppressions() {
  return "leak:libvulkan_lvp.so\nleak:libvulkan.so\nleak:libVkLayer_khronos_validation.so\nleak:libLLVM\n";
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  gFixture = new Fixture;  // lives until exit: the device outlives every input
  gTrace = std::getenv("RAYBRIDGE_FUZZ_TRACE") != nullptr;
  rb::HeadlessDeviceDesc deviceDesc;
  deviceDesc.enableValidation = true;  // when the layer is installed; not required
  auto device = rb::HeadlessDevice::create(deviceDesc);
  if (!device) fail("no headless device: " + device.error().message);
  gFixture->device = std::move(device.value());
  auto context = rb::Context::create(gFixture->device->contextDesc());
  if (!context) fail("no context: " + context.error().message);
  gFixture->context = std::move(context.value());
  rb::AsServiceDesc descs[3];
  descs[1].blasBudgetBytes = 256 << 10;
  descs[1].storageBlockBytes = 64 << 10;
  descs[2].dynamicMode = rb::DynamicBuildMode::AsyncOneFrameLate;  // no queue: the fallback, two copies
  descs[2].refitPolicy.kind = rb::RefitPolicyKind::AlwaysRefit;
  for (int i = 0; i < 3; ++i) {
    auto service = rb::AccelerationStructureService::create(*gFixture->context, descs[i]);
    if (!service) fail("no service: " + service.error().message);
    gFixture->services[i] = std::move(service.value());
  }
  std::fprintf(stderr, "mesh_registration_fuzz: device '%s', validation %s\n", gFixture->device->deviceName().c_str(),
               gFixture->device->validationEnabled() ? "on" : "off");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  const int serviceIndex = in.ConsumeIntegralInRange(0, 2);
  rb::AccelerationStructureService& service = *gFixture->services[serviceIndex];
  if (gTrace) std::fprintf(stderr, "service %d\n", serviceIndex);
  std::vector<Live> live;
  for (int op = 0; op < 32 && in.remaining_bytes() > 0; ++op) {
    switch (in.ConsumeIntegralInRange(0, 4)) {
      case 0:
      case 1: {
        Live l;
        std::string name;
        const rb::MeshDesc d = meshDesc(in, l, name);
        trace("registerMesh", d);
        rb::Result<rb::MeshHandle> h = service.registerMesh(d);
        trace("  ->", h ? h.value() : rb::MeshHandle{}, h ? "ok" : h.error().message);
        if (!h) {
          if (h.error().message.empty()) fail("registerMesh failed without a message");
          break;
        }
        if (h.value().isNull()) fail("registerMesh returned the null handle");
        l.handle = h.value();
        live.push_back(std::move(l));
        break;
      }
      case 2: {
        const rb::MeshHandle h = pickHandle(in, live);
        const rb::Status s = service.releaseMesh(h);
        trace("releaseMesh", h, s ? "ok" : s.error().message);
        auto it = std::find_if(live.begin(), live.end(), [&](const Live& l) { return l.handle == h; });
        if (s.ok() != (it != live.end()))
          fail("releaseMesh({" + std::to_string(h.index) + ", " + std::to_string(h.generation) + "}) " +
               (s.ok() ? "accepted a handle that is not live" : "refused a live handle: " + s.error().message));
        if (it != live.end()) live.erase(it);
        break;
      }
      case 3: {
        const rb::MeshHandle h = pickHandle(in, live);
        rb::MeshUpdate update;
        update.forceRebuild = in.ConsumeBool();
        Live replacement;
        std::string name;
        rb::MeshDesc d;
        if (in.ConsumeBool()) {
          d = meshDesc(in, replacement, name);
          update.desc = &d;
          trace("updateMesh desc", d);
        }
        const rb::Status s = service.updateMesh(h, update);
        trace(update.forceRebuild ? "updateMesh (forceRebuild)" : "updateMesh", h, s ? "ok" : s.error().message);
        if (!s.ok() && s.error().message.empty()) fail("updateMesh failed without a message");
        auto it = std::find_if(live.begin(), live.end(), [&](const Live& l) { return l.handle == h; });
        if (s.ok() && it == live.end()) fail("updateMesh accepted a handle that is not live");
        if (s.ok() && update.desc) {
          it->vertices = std::move(replacement.vertices);
          it->indices = std::move(replacement.indices);
        }
        break;
      }
      default: {
        const rb::MeshHandle h = pickHandle(in, live);
        const bool isLive = std::any_of(live.begin(), live.end(), [&](const Live& l) { return l.handle == h; });
        rb::Result<bool> built = service.isBuilt(h);
        if (built.ok() != isLive) fail("isBuilt disagrees with the handle's liveness");
        if (built.ok() && built.value()) fail("isBuilt is true but nothing was recorded");
        (void)service.blasAddress(h);
        const rb::AsStats stats = service.stats();
        if (stats.meshHandles != live.size())
          fail("stats().meshHandles is " + std::to_string(stats.meshHandles) + " with " + std::to_string(live.size()) +
               " live handles");
        if (stats.nonOpaqueMeshes != service.nonOpaqueMeshCount()) fail("nonOpaqueMeshCount() differs from stats()");
        break;
      }
    }
  }
  for (const Live& l : live)
    if (rb::Status s = service.releaseMesh(l.handle); !s) fail("releasing a live handle failed: " + s.error().message);
  const rb::AsStats stats = service.stats();
  if (stats.meshHandles != 0 || stats.blasCount != 0)
    fail("after releasing every handle: " + std::to_string(stats.meshHandles) + " handles, " +
         std::to_string(stats.blasCount) + " BLASes (nothing was built, so nothing can be cached)");
  checkValidation();
  return 0;
}
