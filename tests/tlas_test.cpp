// TLAS: 10,000 instances build and trace correctly; refits; instances of meshes not yet built are skipped.
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <cstring>

#include "as_service_impl.h"
#include "test_scene.h"

using namespace rbtest;

TEST_CASE("a 10,000-instance TLAS builds and traces like Embree", "[as][tlas][embree]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  TestScene scene;
  const float mn[3] = {-0.4f, 0.0f, -0.4f}, mx[3] = {0.4f, 1.0f, 0.4f};
  scene.meshes.push_back(rbsamples::makeBox(mn, mx));
  scene.meshes.push_back(rbsamples::makeSphere(0.45f, 12, 6));
  scene.meshes.push_back(rbsamples::makeGrid(120.0f, 8));  // ground, so the gaps between instances hit too
  for (int z = 0; z < 100; ++z) {
    for (int x = 0; x < 100; ++x) {
      // Heights vary so neighbouring instances overlap in view and the nearest one must win.
      float height = 0.5f + 0.5f * float((x * 7 + z * 13) % 5);
      std::array<float, 12> t = {1, 0, 0, float(x) - 49.5f, 0, height, 0, 0, 0, 0, 1, float(z) - 49.5f};
      scene.instances.push_back({uint32_t((x + z) % 2), t});
    }
  }
  scene.instances.push_back({2, translation(0, 0, 0)});
  BuiltScene built = buildScene(fx, *service.value(), scene);
  CHECK(built.tlas.instanceCount == 10001);
  CHECK(service.value()->stats().blasCount == 3);
  CHECK(service.value()->stats().lastTlasInstances == 10001);

  rb::PrimaryRayCamera cam;
  // Close enough that instances span many pixels, looking across the field so thousands of them are in view.
  float eye[3] = {-52.0f, 9.0f, -52.0f}, target[3] = {-38.0f, 0.0f, -40.0f};
  std::memcpy(cam.eye, eye, sizeof eye);
  std::memcpy(cam.target, target, sizeof target);
  cam.verticalFovDegrees = 60.0f;
  TraceComparison c = compareFirstTrace(fx, scene, built.tlas.tlas, cam, 256, 192);
  INFO("compared " << c.compared << ", silhouettes " << c.silhouettes << ", hits " << c.hits);
  REQUIRE(c.hits > 1000);
  CHECK(double(c.hitMissAgree) / c.compared >= 0.999);
  CHECK(double(c.distanceAgree) / c.hitsCompared >= 0.999);
  CHECK(double(c.sameInstance) / c.hitsCompared >= 0.999);
  destroyScene(fx, built);
}

TEST_CASE("TLAS refits when only transforms change and rebuilds when the meshes change", "[as][tlas]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  TestScene scene = makeConformanceScene();
  BuiltScene built = buildScene(fx, s, scene, kRebuildTlas);
  rb::TlasBuildOptions update;
  update.mode = rb::TlasBuildMode::UpdateIfPossible;

  rb::TlasInfo first, second, third;
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto t = s.recordTlasBuild(cmd, built.instances, update);
    RB_REQUIRE_OK(t);
    first = t.value();
  });
  CHECK(!first.updated);  // the previous TLAS was built without ALLOW_UPDATE
  // Move the sphere instance up by 0.5: same meshes in the same order, so a refit is valid.
  built.instances[1].transform[7] += 0.5f;
  scene.instances[1].transform[7] += 0.5f;
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto t = s.recordTlasBuild(cmd, built.instances, update);
    RB_REQUIRE_OK(t);
    second = t.value();
  });
  CHECK(second.updated);
  // The refit TLAS traces like Embree over the moved scene.
  TraceComparison c = compareFirstTrace(fx, scene, second.tlas, conformanceCamera(), 96, 64);
  CHECK(double(c.hitMissAgree) / c.compared >= 0.999);
  CHECK(double(c.distanceAgree) / c.hitsCompared >= 0.999);

  // Swapping which mesh an instance uses invalidates the refit.
  std::swap(built.instances[1].mesh, built.instances[3].mesh);
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto t = s.recordTlasBuild(cmd, built.instances, update);
    RB_REQUIRE_OK(t);
    third = t.value();
  });
  CHECK(!third.updated);
  destroyScene(fx, built);
}

TEST_CASE("TLAS refits only over a TLAS built with the same build preference", "[as][tlas]") {
  // Found by the soak (raybridge-bench --scenario soak): a refit over a TLAS last built with the other preference
  // repeated different flags (VUID-vkCmdBuildAccelerationStructuresKHR-pInfos-03759); the fixture fails the test
  // on that validation error.
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  TestScene scene = makeConformanceScene();
  BuiltScene built = buildScene(fx, s, scene);
  auto build = [&](rb::TlasBuildPreference preference) {
    rb::TlasBuildOptions o;
    o.mode = rb::TlasBuildMode::UpdateIfPossible;
    o.preference = preference;
    rb::TlasInfo info;
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto t = s.recordTlasBuild(cmd, built.instances, o);
      RB_REQUIRE_OK(t);
      info = t.value();
    });
    return info;
  };
  (void)build(rb::TlasBuildPreference::FastTrace);
  CHECK(build(rb::TlasBuildPreference::FastTrace).updated);
  CHECK(!build(rb::TlasBuildPreference::FastBuild).updated);  // new flags: a rebuild
  CHECK(build(rb::TlasBuildPreference::FastBuild).updated);
  CHECK(!build(rb::TlasBuildPreference::FastTrace).updated);
  destroyScene(fx, built);
}

namespace {

// The bytes of `buffer` (the TLAS's shading records, host-visible or device-local), through a copy into a host
// buffer recorded after the frame's TLAS build.
std::vector<uint8_t> copyBack(GpuFixture& fx, VkBuffer buffer, VkDeviceSize bytes) {
  auto readback = rb::createBuffer(fx.ctx(), bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, rb::MemoryLocation::HostVisible,
                                   rb::MemoryCategory::PassBuffers, "test readback");
  RB_REQUIRE_OK(readback);
  rb::GpuBuffer host = readback.value();
  fx.runAndSettle([&](VkCommandBuffer cmd) {
    const VkBufferCopy region{0, 0, bytes};
    fx.vk().vkCmdCopyBuffer(cmd, buffer, host.buffer, 1, &region);
    VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    b.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    fx.vk().vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &b, 0, nullptr,
                                 0, nullptr);
  });
  const auto* p = static_cast<const uint8_t*>(host.mapped);
  std::vector<uint8_t> out(p, p + bytes);
  rb::destroyBuffer(fx.ctx(), host);
  return out;
}

// The shading records with their buffer addresses checked against the instance's own upload, then zeroed: each
// variant uploads new buffers, whose addresses repeat only when the allocator happens to hand out the same
// memory again (AddressSanitizer's quarantine of freed memory, lavapipe's device memory, makes them differ).
std::vector<uint8_t> recordsWithoutAddresses(const std::vector<uint8_t>& bytes, const TestScene& scene,
                                             const BuiltScene& built) {
  REQUIRE(bytes.size() % sizeof(rb::ShadingRecord) == 0);
  std::vector<rb::ShadingRecord> records(bytes.size() / sizeof(rb::ShadingRecord));
  std::memcpy(records.data(), bytes.data(), bytes.size());
  REQUIRE(records.size() >= scene.instances.size());
  for (size_t i = 0; i < scene.instances.size(); ++i) {
    INFO("instance " << i);
    const rb::MeshDesc& mesh = built.uploads[scene.instances[i].mesh].desc;
    rb::ShadingRecord& r = records[i];
    CHECK(r.positions == mesh.vertexAddress);
    CHECK(r.indices == mesh.indexAddress);
    CHECK(r.normals == mesh.normalAddress);
    CHECK(r.texcoords == mesh.texcoordAddress);
    r.positions = r.indices = r.normals = r.texcoords = 0;
  }
  std::vector<uint8_t> out(bytes.size());
  std::memcpy(out.data(), records.data(), bytes.size());
  return out;
}

}  // namespace

TEST_CASE("every instance upload and build preference traces like Embree, with the same shading records",
          "[as][tlas][embree]") {
  // Lavapipe's host memory is device-local, so Auto reads in place here: CopyToDevice exercises the copy (the
  // default on a discrete GPU) under validation, FastBuild the other build flag.
  GpuFixture fx;
  const TestScene scene = makeConformanceScene();
  struct Variant {
    const char* name;
    rb::TlasInstanceUpload upload;
    rb::TlasBuildPreference preference;
  };
  std::vector<uint8_t> inPlaceRecords;
  VkDeviceSize inPlaceTlasBytes = 0;
  for (const Variant& v :
       {Variant{"in place", rb::TlasInstanceUpload::ReadInPlace, rb::TlasBuildPreference::FastTrace},
        Variant{"device copy", rb::TlasInstanceUpload::CopyToDevice, rb::TlasBuildPreference::FastTrace},
        Variant{"copy, fast build", rb::TlasInstanceUpload::CopyToDevice, rb::TlasBuildPreference::FastBuild}}) {
    INFO(v.name);
    auto service = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(service);
    rb::TlasBuildOptions options;
    options.instanceUpload = v.upload;
    options.preference = v.preference;
    options.writeShadingRecords = true;
    BuiltScene built = buildScene(fx, *service.value(), scene, options);
    REQUIRE(built.tlas.shadingRecords != VK_NULL_HANDLE);
    TraceComparison c = compareFirstTrace(fx, scene, built.tlas.tlas, conformanceCamera(), 96, 64);
    REQUIRE(c.hits > 100);
    CHECK(double(c.hitMissAgree) / c.compared >= 0.999);
    CHECK(double(c.distanceAgree) / c.hitsCompared >= 0.999);
    CHECK(double(c.sameInstance) / c.hitsCompared >= 0.999);
    const std::vector<uint8_t> records =
        recordsWithoutAddresses(copyBack(fx, built.tlas.shadingRecords, built.tlas.shadingRecordsBytes), scene, built);
    if (inPlaceRecords.empty()) {
      inPlaceRecords = records;
    } else {
      CHECK(records == inPlaceRecords);
    }
    // The device copies count as TLAS memory: more than reading in place with the same build flags.
    const VkDeviceSize tlasBytes = service.value()->stats().tlasBytes;
    if (v.upload == rb::TlasInstanceUpload::ReadInPlace) inPlaceTlasBytes = tlasBytes;
    if (v.upload == rb::TlasInstanceUpload::CopyToDevice && v.preference == rb::TlasBuildPreference::FastTrace)
      CHECK(tlasBytes > inPlaceTlasBytes);
    destroyScene(fx, built);
  }
  // A value outside the enum is a named error, not a build.
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  rb::TlasBuildOptions bad;
  bad.instanceUpload = static_cast<rb::TlasInstanceUpload>(7);
  fx.runFrame([&](VkCommandBuffer cmd) {
    auto t = service.value()->recordTlasBuild(cmd, {}, bad);
    REQUIRE_FALSE(t);
    CHECK(t.error().message.find("options.instanceUpload (7)") != std::string::npos);
  });
}

TEST_CASE("instances of meshes still queued are skipped, never referenced", "[as][tlas]") {
  GpuFixture fx;
  rb::AsServiceDesc desc;
  desc.maxBuildTrianglesPerCall = 1;  // one build per call
  auto service = rb::AccelerationStructureService::create(fx.ctx(), desc);
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  UploadedMesh a = fx.upload(rbsamples::makeSphere(1, 8, 4)), b = fx.upload(rbsamples::makeGrid(2, 4));
  auto ha = s.registerMesh(a.desc), hb = s.registerMesh(b.desc);
  RB_REQUIRE_OK(ha);
  RB_REQUIRE_OK(hb);
  std::vector<rb::Instance> inst(2);
  inst[0].mesh = ha.value();
  inst[1].mesh = hb.value();
  rb::TlasInfo info;
  uint32_t left = 99;
  auto frame = [&] {  // builds within the budget, then the TLAS over both instances
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto l = s.recordPendingWork(cmd);
      RB_REQUIRE_OK(l);
      left = l.value();
      auto t = s.recordTlasBuild(cmd, inst);
      RB_REQUIRE_OK(t);
      info = t.value();
    });
  };
  frame();
  CHECK(left == 1);
  CHECK(info.instanceCount == 1);
  CHECK(info.skippedInstances == 1);
  CHECK(s.isBuilt(ha.value()).value());
  CHECK(!s.isBuilt(hb.value()).value());
  frame();
  CHECK(left == 0);
  CHECK(info.instanceCount == 2);
  CHECK(info.skippedInstances == 0);
  fx.destroy(a);
  fx.destroy(b);
}

TEST_CASE("a dynamic mesh is refit in place after its vertices change", "[as][dynamic]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(4.0f, 8));
  scene.instances.push_back({0, translation(0, 0, 0)});
  UploadedMesh m = fx.upload(scene.meshes[0]);
  m.desc.role = rb::MeshRole::Dynamic;
  // Host-visible vertices so the "engine" can deform them in place.
  fx.device().destroyBuffer(m.vertices);
  auto v = fx.device().createBuffer(scene.meshes[0].positions.size() * 4,
                                    VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                        VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR,
                                    true, scene.meshes[0].positions.data());
  RB_REQUIRE_OK(v);
  m.vertices = v.value();
  m.desc.vertexAddress = m.vertices.address;
  auto h = s.registerMesh(m.desc);
  RB_REQUIRE_OK(h);
  rb::Instance inst;
  inst.mesh = h.value();
  rb::TlasInfo tlas;
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    tlas = s.recordTlasBuild(cmd, std::span(&inst, 1)).value();
  });
  // Lift the whole grid by 1.5 and refit.
  float* p = static_cast<float*>(m.vertices.mapped);
  for (size_t i = 1; i < scene.meshes[0].positions.size(); i += 3) p[i] += 1.5f;
  for (size_t i = 1; i < scene.meshes[0].positions.size(); i += 3) scene.meshes[0].positions[i] += 1.5f;
  RB_REQUIRE_OK(s.updateMesh(h.value()));
  fx.runFrame([&](VkCommandBuffer cmd) {
    RB_REQUIRE_OK(s.recordPendingWork(cmd));
    tlas = s.recordTlasBuild(cmd, std::span(&inst, 1)).value();
  });
  rb::PrimaryRayCamera cam;
  float eye[3] = {0.3f, 6.0f, 0.2f}, target[3] = {0, 0, 0};
  std::memcpy(cam.eye, eye, sizeof eye);
  std::memcpy(cam.target, target, sizeof target);
  TraceComparison c = compareFirstTrace(fx, scene, tlas.tlas, cam, 64, 64);
  REQUIRE(c.hitsCompared > 100);
  CHECK(c.distanceAgree == c.hitsCompared);  // distances match the lifted grid, not the original

  // A static mesh cannot be refit.
  UploadedMesh st = fx.upload(rbsamples::makeSphere(1, 8, 4));
  auto hs = s.registerMesh(st.desc);
  RB_REQUIRE_OK(hs);
  auto bad = s.updateMesh(hs.value());
  REQUIRE(!bad.ok());
  CHECK(bad.error().message.find("MeshRole::Dynamic") != std::string::npos);
  fx.destroy(st);
  fx.destroy(m);
}
