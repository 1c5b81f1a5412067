// Bad input returns a clear error naming the problem (or, for NaN vertices, is handled as Vulkan specifies),
// never a crash or a validation error.
#include <catch2/catch_test_macros.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "test_scene.h"

using namespace rbtest;

namespace {
bool mentions(const rb::Error& e, const char* what) { return e.message.find(what) != std::string::npos; }
}  // namespace

TEST_CASE("invalid mesh descriptions are rejected with a message naming the problem", "[as][bad-input]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  UploadedMesh m = fx.upload(rbsamples::makeSphere(1, 8, 4));
  auto expectError = [&](rb::MeshDesc d, const char* mention) {
    d.debugName = "bad mesh";
    auto r = s.registerMesh(d);
    REQUIRE(!r.ok());
    INFO(r.error().message);
    CHECK(r.error().code == rb::ErrorCode::InvalidArgument);
    CHECK(mentions(r.error(), mention));
    CHECK(mentions(r.error(), "bad mesh"));
  };

  SECTION("zero triangles") {
    rb::MeshDesc d = m.desc;
    d.triangleCount = 0;
    expectError(d, "triangleCount is 0");
  }
  SECTION("index count beyond the declared index buffer") {
    rb::MeshDesc d = m.desc;
    d.triangleCount += 1;
    expectError(d, "indexBufferBytes");
  }
  SECTION("vertex count beyond the declared vertex buffer") {
    rb::MeshDesc d = m.desc;
    d.vertexBufferBytes -= 4;
    expectError(d, "vertexBufferBytes");
  }
  SECTION("an index past the vertex range, caught from the host copy") {
    rbsamples::CpuMesh bad = rbsamples::makeSphere(1, 8, 4);
    bad.indices[5] = bad.vertexCount() + 7;
    UploadedMesh b = fx.upload(bad);
    expectError(b.desc, "index 5");
    fx.destroy(b);
  }
  SECTION("a null vertex address") {
    rb::MeshDesc d = m.desc;
    d.vertexAddress = 0;
    expectError(d, "vertexAddress is 0");
  }
  SECTION("a null index address") {
    rb::MeshDesc d = m.desc;
    d.indexAddress = 0;
    expectError(d, "indexAddress is 0");
  }
  SECTION("an unsupported vertex format") {
    rb::MeshDesc d = m.desc;
    d.vertexFormat = VK_FORMAT_R8_UNORM;
    expectError(d, "vertexFormat");
  }
  SECTION("a stride smaller than the format") {
    rb::MeshDesc d = m.desc;
    d.vertexStride = 8;
    expectError(d, "vertexStride");
  }
  SECTION("non-indexed with too few vertices") {
    rb::MeshDesc d = m.desc;
    d.indexType = rb::IndexType::None;
    d.triangleCount = d.vertexCount;  // needs 3x the vertices
    expectError(d, "non-indexed");
  }
  CHECK(s.stats().blasCount == 0);  // nothing was queued by the rejected calls
  fx.destroy(m);
}

// Regression tests of what tests/fuzz/mesh_registration_fuzz found. Each names the committed input
// (tests/fuzz/corpus/mesh_registration/crash-*) that the fuzzer decodes into the MeshDesc written out here.

TEST_CASE("a vertexFormat that is no VkFormat is refused before the driver sees it", "[as][bad-input][fuzz]") {
  // crash-vertex-format-255 (ff 00 00 71): registerMesh with vertexFormat 255 and every other field zero. The
  // format went to vkGetPhysicalDeviceFormatProperties first (a validation error: no valid VkFormat value).
  GpuFixture fx;  // fails the test on any validation error
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  rb::MeshDesc d;
  d.vertexFormat = VkFormat(255);
  auto r = service.value()->registerMesh(d);
  REQUIRE(!r.ok());
  INFO(r.error().message);
  CHECK(r.error().code == rb::ErrorCode::InvalidArgument);
  CHECK(mentions(r.error(), "vertexFormat"));
  CHECK(mentions(r.error(), "(255)"));
}

TEST_CASE("a registration's debugName need not outlive registerMesh", "[as][bad-input][fuzz]") {
  // crash-debug-name-lifetime: a static mesh registered with a debugName whose string then went away, then
  // updateMesh on it; the service had kept the pointer and read it for the error message (use after scope).
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  rb::MeshDesc d;  // the fuzzer's fields: only counts and addresses, nothing is built
  d.vertexStride = 0x80000000u;
  d.vertexCount = 61;
  d.triangleCount = 20;
  d.indexType = rb::IndexType::None;
  d.vertexAddress = 0xd2ba101;
  d.vertexBufferBytes = 130996502528ull;
  d.indexBufferBytes = 240;
  d.normalStride = 9;
  d.texcoordStride = 7;
  std::string name = "fuzzed mesh";
  d.debugName = name.c_str();
  auto h = s.registerMesh(d);
  RB_REQUIRE_OK(h);
  std::fill(name.begin(), name.end(), '#');  // the engine reuses its string
  rb::Status u = s.updateMesh(h.value());
  REQUIRE(!u.ok());
  INFO(u.error().message);
  CHECK(mentions(u.error(), "mesh 'fuzzed mesh' was registered with MeshRole::Static"));
  RB_REQUIRE_OK(s.releaseMesh(h.value()));
}

TEST_CASE("host indices at an unaligned address are read, not dereferenced as uint32_t", "[as][bad-input][fuzz]") {
  // crash-unaligned-host-indices: 21845 uint32 indices one byte past an aligned address (UBSan: misaligned
  // load). MeshDesc::hostIndices asks for no alignment; a stray index must still be caught.
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  rb::MeshDesc d;
  d.vertexFormat = VK_FORMAT_R32G32_SFLOAT;
  d.vertexStride = 32;
  d.vertexCount = 65536;
  d.triangleCount = 21845;
  d.vertexAddress = 0x9baee01;
  d.indexAddress = 0x6f3ea00;
  d.vertexBufferBytes = 2097152;
  d.indexBufferBytes = 262140;
  std::vector<unsigned char> storage(1 + size_t(d.triangleCount) * 3 * 4);
  for (uint32_t i = 0; i < d.triangleCount * 3; ++i) {
    const uint32_t index = i == 5 ? d.vertexCount + 7 : i % d.vertexCount;
    std::memcpy(storage.data() + 1 + size_t(i) * 4, &index, 4);
  }
  d.hostIndices = storage.data() + 1;
  auto r = service.value()->registerMesh(d);
  REQUIRE(!r.ok());
  INFO(r.error().message);
  CHECK(mentions(r.error(), "index 5 is 65543 but vertexCount is 65536"));
  // Uint16 indices at an odd address, all in range: accepted.
  d.indexType = rb::IndexType::Uint16;
  d.indexBufferBytes = size_t(d.triangleCount) * 3 * 2;
  for (uint32_t i = 0; i < d.triangleCount * 3; ++i) {
    const uint16_t index = uint16_t(i);
    std::memcpy(storage.data() + 1 + size_t(i) * 2, &index, 2);
  }
  auto ok = service.value()->registerMesh(d);
  RB_REQUIRE_OK(ok);
  RB_REQUIRE_OK(service.value()->releaseMesh(ok.value()));
}

TEST_CASE("stale and null handles are rejected", "[as][bad-input]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  UploadedMesh m = fx.upload(rbsamples::makeSphere(1, 8, 4));
  auto h = s.registerMesh(m.desc);
  RB_REQUIRE_OK(h);
  RB_REQUIRE_OK(s.releaseMesh(h.value()));
  rb::Instance inst;
  inst.mesh = h.value();
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto t = s.recordTlasBuild(cmd, std::span(&inst, 1));
    REQUIRE(!t.ok());
    CHECK(t.error().code == rb::ErrorCode::StaleHandle);
    CHECK(mentions(t.error(), "instances[0]"));
    inst.mesh = rb::MeshHandle{};
    auto n = s.recordTlasBuild(cmd, std::span(&inst, 1));
    REQUIRE(!n.ok());
    CHECK(mentions(n.error(), "null"));
  });
  auto twice = s.releaseMesh(h.value());
  REQUIRE(!twice.ok());
  CHECK(twice.error().code == rb::ErrorCode::StaleHandle);
  fx.destroy(m);
}

TEST_CASE("NaN vertices make their triangles inactive, as Vulkan specifies", "[as][bad-input]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  // Two quads side by side; the left one has a NaN vertex in each of its triangles.
  TestScene scene;
  rbsamples::CpuMesh grid = rbsamples::makeGrid(2.0f, 2);  // 3x3 vertices, 8 triangles
  scene.meshes.push_back(grid);
  scene.instances.push_back({0, translation(0, 0, 0)});
  rbsamples::CpuMesh poisoned = grid;
  // Vertex 0 (corner -1,-1) only touches the first quad's triangles.
  poisoned.positions[0] = std::numeric_limits<float>::quiet_NaN();
  UploadedMesh uploaded = fx.upload(poisoned);
  auto h = service.value()->registerMesh(uploaded.desc);
  RB_REQUIRE_OK(h);
  rb::Instance inst;
  inst.mesh = h.value();
  rb::TlasInfo tlas;
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(service.value()->recordPendingWork(cmd));
    tlas = service.value()->recordTlasBuild(cmd, std::span(&inst, 1)).value();
  });
  // Look straight down: the quad with the NaN vertex must not be hit, the others are.
  auto pass = rb::PrimaryRayPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  const uint32_t W = 32, H = 32;
  rb::GpuImage dist = fx.makeImage(W, H, VK_FORMAT_R32_SFLOAT), ids = fx.makeImage(W, H, VK_FORMAT_R32G32_UINT);
  rb::PrimaryRayCamera cam;
  float eye[3] = {0, 4, 0}, target[3] = {0, 0, 0}, up[3] = {0, 0, -1};
  std::memcpy(cam.eye, eye, sizeof eye);
  std::memcpy(cam.target, target, sizeof target);
  std::memcpy(cam.upHint, up, sizeof up);
  cam.verticalFovDegrees = 20.0f;  // sees only the inner 1.4 x 1.4 around the centre
  fx.runFrame([&](VkCommandBuffer cmd) {
    fx.toGeneral(cmd, dist);
    fx.toGeneral(cmd, ids);
    RB_REQUIRE_OK(pass.value()->record(cmd, {.tlas = tlas, .camera = cam, .targets = {dist.view, ids.view, W, H}}));
  });
  auto d = fx.readImage(dist, 4);
  const float* t = reinterpret_cast<const float*>(d.data());
  // Vertex 0 at (-1, 0, -1) belongs to one triangle only: (-1,-1), (-1,0), (0,-1) in (x, z), i.e. x + z < -1.
  auto basis = rb::computeCameraBasis(cam, W, H);
  RB_REQUIRE_OK(basis);
  const rb::CameraBasis& b = basis.value();
  uint32_t inactiveHits = 0, inactivePixels = 0, activeHits = 0, activePixels = 0;
  for (uint32_t y = 0; y < H; ++y) {
    for (uint32_t x = 0; x < W; ++x) {
      float nx = (x + 0.5f) / W * 2 - 1, ny = (y + 0.5f) / H * 2 - 1;
      float dir[3];
      for (int i = 0; i < 3; ++i) dir[i] = b.forward[i] + nx * b.right[i] - ny * b.up[i];
      float s = -b.eye[1] / dir[1];
      float wx = b.eye[0] + s * dir[0], wz = b.eye[2] + s * dir[2];
      bool hit = t[y * W + x] > 0;
      if (wx + wz < -1.05f) {
        ++inactivePixels;
        inactiveHits += hit;
      } else if (wx + wz > -0.95f) {
        ++activePixels;
        activeHits += hit;
      }
    }
  }
  REQUIRE(inactivePixels > 20);
  CHECK(inactiveHits == 0);
  CHECK(activeHits == activePixels);
  fx.destroyImage(dist);
  fx.destroyImage(ids);
  fx.destroy(uploaded);
}

TEST_CASE("context creation names what is missing", "[context][bad-input]") {
  rb::ContextDesc empty;
  auto r = rb::Context::create(empty);
  REQUIRE(!r.ok());
  CHECK(r.error().code == rb::ErrorCode::InvalidArgument);
  CHECK(mentions(r.error(), "ContextDesc::instance"));

  GpuFixture fx;
  rb::ContextDesc d = fx.device().contextDesc();
  d.device = VK_NULL_HANDLE;
  r = rb::Context::create(d);
  REQUIRE(!r.ok());
  CHECK(mentions(r.error(), "ContextDesc::device"));
  d = fx.device().contextDesc();
  d.framesInFlight = 9;
  r = rb::Context::create(d);
  REQUIRE(!r.ok());
  CHECK(mentions(r.error(), "framesInFlight"));

  // A camera with eye == target is refused by the pass, before any GPU work.
  rb::PrimaryRayCamera cam;
  cam.target[2] = 0.0f;
  auto basis = rb::computeCameraBasis(cam, 4, 4);
  REQUIRE(!basis.ok());
  CHECK(mentions(basis.error(), "eye equals target"));
  CHECK(!rb::computeCameraBasis(rb::PrimaryRayCamera{}, 0, 4).ok());
}

TEST_CASE("invocation reorder is enabled only where the device has it", "[context][invocation_reorder]") {
  GpuFixture fx;
  rb::HeadlessDevice& dev = fx.device();
  const bool supported = rb::supportsInvocationReorder(dev.instance(), dev.physicalDevice(), dev.getInstanceProcAddr());
  // The headless device enables it wherever it can, and tells the context.
  CHECK(dev.invocationReorderEnabled() == supported);
  CHECK(fx.ctx().deviceInfo().invocationReorder == supported);
  CHECK(!rb::supportsInvocationReorder(VK_NULL_HANDLE, dev.physicalDevice(), dev.getInstanceProcAddr()));
  rb::ContextDesc d = dev.contextDesc();
  d.invocationReorderEnabled = true;
  auto r = rb::Context::create(d);
  if (supported) {
    RB_REQUIRE_OK(r);
    CHECK(r.value()->deviceInfo().invocationReorder);
    SKIP("the device supports VK_NV_ray_tracing_invocation_reorder: no mismatch to report");
  }
  // Claimed on a device without it: a named error, not a pipeline failure later.
  REQUIRE(!r.ok());
  CHECK(r.error().code == rb::ErrorCode::MissingExtension);
  CHECK(mentions(r.error(), "invocationReorderEnabled"));
  CHECK(mentions(r.error(), "VK_NV_ray_tracing_invocation_reorder"));
}

TEST_CASE("the headless device picks a ray tracing device and honours the name filter", "[context]") {
  rb::HeadlessDeviceDesc desc;
  desc.deviceNameFilter = "no-such-device-xyz";
  auto r = rb::HeadlessDevice::create(desc);
  REQUIRE(!r.ok());
  CHECK(r.error().code == rb::ErrorCode::NoSuitableDevice);
  CHECK(mentions(r.error(), "no-such-device-xyz"));
}

TEST_CASE("the validation layer is on in tests and its errors are counted", "[context][validation]") {
  // A deliberate API misuse on a device of its own (the fixture's would fail the test, as it should).
  rb::HeadlessDeviceDesc desc;
  desc.enableValidation = true;
  desc.requireValidation = true;
  auto dev = rb::HeadlessDevice::create(desc);
  RB_REQUIRE_OK(dev);
  REQUIRE(dev.value()->validationEnabled());
  auto createBuffer = reinterpret_cast<PFN_vkCreateBuffer>(dev.value()->deviceProc("vkCreateBuffer"));
  auto destroyBuffer = reinterpret_cast<PFN_vkDestroyBuffer>(dev.value()->deviceProc("vkDestroyBuffer"));
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = 0;  // invalid: size must be greater than 0
  info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  VkResult result = createBuffer(dev.value()->device(), &info, nullptr, &buffer);
  if (result == VK_SUCCESS && buffer) destroyBuffer(dev.value()->device(), buffer, nullptr);
  CHECK(dev.value()->validationErrorCount() >= 1);
}
