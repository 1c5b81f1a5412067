// The SDK owns lifetimes: passes and denoisers destroyed right after recording, while their frame is still in
// flight, hand their Vulkan objects to the context, which frees them once the frames in flight are done. No
// wait-idle, no retire list in the caller; validation (fatal in the fixture) stays clean and memory stays bounded.
#include <catch2/catch_test_macros.hpp>

#include <algorithm>
#include <vector>

#include "context_impl.h"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

// The engine's side of frames in flight: one command buffer and one fence per frame slot, submitted without
// waiting; a slot's fence is waited for before the slot is reused (before beginFrame), as engines do.
class FrameRing {
 public:
  FrameRing(GpuFixture& fx, uint32_t slots) : fx_(fx) {
    rb::HeadlessDevice& d = fx.device();
    createPool_ = proc<PFN_vkCreateCommandPool>("vkCreateCommandPool");
    destroyPool_ = proc<PFN_vkDestroyCommandPool>("vkDestroyCommandPool");
    allocate_ = proc<PFN_vkAllocateCommandBuffers>("vkAllocateCommandBuffers");
    begin_ = proc<PFN_vkBeginCommandBuffer>("vkBeginCommandBuffer");
    end_ = proc<PFN_vkEndCommandBuffer>("vkEndCommandBuffer");
    reset_ = proc<PFN_vkResetCommandBuffer>("vkResetCommandBuffer");
    createFence_ = proc<PFN_vkCreateFence>("vkCreateFence");
    destroyFence_ = proc<PFN_vkDestroyFence>("vkDestroyFence");
    waitFences_ = proc<PFN_vkWaitForFences>("vkWaitForFences");
    resetFences_ = proc<PFN_vkResetFences>("vkResetFences");
    submit_ = proc<PFN_vkQueueSubmit>("vkQueueSubmit");
    VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pi.queueFamilyIndex = d.queueFamily();
    REQUIRE(createPool_(d.device(), &pi, nullptr, &pool_) == VK_SUCCESS);
    cmds_.resize(slots);
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool_;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = slots;
    REQUIRE(allocate_(d.device(), &ai, cmds_.data()) == VK_SUCCESS);
    fences_.resize(slots);
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fi.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    for (VkFence& f : fences_) REQUIRE(createFence_(d.device(), &fi, nullptr, &f) == VK_SUCCESS);
  }
  ~FrameRing() {
    VkDevice device = fx_.device().device();
    (void)fx_.device().waitIdle();
    for (VkFence f : fences_) destroyFence_(device, f, nullptr);
    destroyPool_(device, pool_, nullptr);
  }

  // Waits for the slot's previous submission, then starts its command buffer. Call beginFrame after this.
  VkCommandBuffer acquire(uint32_t slot) {
    VkDevice device = fx_.device().device();
    REQUIRE(waitFences_(device, 1, &fences_[slot], VK_TRUE, UINT64_MAX) == VK_SUCCESS);
    REQUIRE(resetFences_(device, 1, &fences_[slot]) == VK_SUCCESS);
    REQUIRE(reset_(cmds_[slot], 0) == VK_SUCCESS);
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    REQUIRE(begin_(cmds_[slot], &bi) == VK_SUCCESS);
    return cmds_[slot];
  }
  // Ends and submits the slot's command buffer, signalling its fence; returns at once.
  void submit(uint32_t slot) {
    REQUIRE(end_(cmds_[slot]) == VK_SUCCESS);
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmds_[slot];
    REQUIRE(submit_(fx_.device().queue(), 1, &si, fences_[slot]) == VK_SUCCESS);
  }

 private:
  template <typename Fn>
  Fn proc(const char* name) {
    auto fn = reinterpret_cast<Fn>(fx_.device().deviceProc(name));
    REQUIRE(fn != nullptr);
    return fn;
  }
  GpuFixture& fx_;
  VkCommandPool pool_ = VK_NULL_HANDLE;
  std::vector<VkCommandBuffer> cmds_;
  std::vector<VkFence> fences_;
  PFN_vkCreateCommandPool createPool_ = nullptr;
  PFN_vkDestroyCommandPool destroyPool_ = nullptr;
  PFN_vkAllocateCommandBuffers allocate_ = nullptr;
  PFN_vkBeginCommandBuffer begin_ = nullptr;
  PFN_vkEndCommandBuffer end_ = nullptr;
  PFN_vkResetCommandBuffer reset_ = nullptr;
  PFN_vkCreateFence createFence_ = nullptr;
  PFN_vkDestroyFence destroyFence_ = nullptr;
  PFN_vkWaitForFences waitFences_ = nullptr;
  PFN_vkResetFences resetFences_ = nullptr;
  PFN_vkQueueSubmit submit_ = nullptr;
};

// What the passes and denoisers own: their images, their buffers (ray counters) and shader binding tables.
VkDeviceSize passBytes(const rb::MemoryStats& m) {
  return m.of(rb::MemoryCategory::PassImages) + m.of(rb::MemoryCategory::PassBuffers) +
         m.of(rb::MemoryCategory::ShaderTables);
}

}  // namespace

TEST_CASE("passes and denoisers destroyed while their frame is in flight are released by the context", "[lifetime]") {
  GpuFixture fx;
  const uint32_t framesInFlight = fx.ctx().framesInFlight();
  const uint32_t frames = 100;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view = conformanceView(48, 32);
  CpuGBuffer cpu = traceGBuffer(embree, view);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);
  const rb::GBufferDesc desc = gbuffer.desc();
  // Whatever setting up retired (build scratch) goes first, so the baseline holds only what stays.
  REQUIRE(fx.device().waitIdle().ok());
  fx.ctx().releaseAfterIdle();
  const rb::MemoryStats start = fx.ctx().memoryStats();

  rb::Light sun;
  sun.direction[0] = 0.4f;
  sun.direction[1] = 1.0f;
  sun.direction[2] = 0.3f;
  sun.angularRadiusDegrees = 2.0f;  // soft: several rays per pixel, so each frame keeps the GPU busy a while
  rb::AoSettings ao;
  ao.range = 2.0f;

  FrameRing ring(fx, framesInFlight);
  VkDeviceSize perFrame = 0;  // pass memory of one frame's shadow pass, AO pass and denoiser
  VkDeviceSize peak = 0;
  for (uint32_t frame = 0; frame < frames; ++frame) {
    const uint32_t slot = frame % framesInFlight;
    VkCommandBuffer cmd = ring.acquire(slot);  // the frame this slot held before is done
    fx.ctx().beginFrame();
    {
      auto shadowPass = rb::ShadowPass::create(fx.ctx());
      RB_REQUIRE_OK(shadowPass);
      auto aoPass = rb::AoPass::create(fx.ctx());
      RB_REQUIRE_OK(aoPass);
      auto denoiser = rb::Denoiser::create(fx.ctx());
      RB_REQUIRE_OK(denoiser);
      RB_REQUIRE_OK(shadowPass.value()->record(cmd, {.gbuffer = desc, .tlas = built.tlas, .light = sun}));
      RB_REQUIRE_OK(aoPass.value()->record(cmd, {.gbuffer = desc, .tlas = built.tlas, .settings = ao}));
      RB_REQUIRE_OK(denoiser.value()->record(cmd, {.gbuffer = desc, .signal = aoPass.value()->outputs().aoView}));
      ring.submit(slot);
      if (frame == 0) perFrame = passBytes(fx.ctx().memoryStats()) - passBytes(start);
    }  // destroyed here, before the GPU has finished the frame, with no wait
    const rb::MemoryStats now = fx.ctx().memoryStats();
    const VkDeviceSize held = passBytes(now) - passBytes(start);
    peak = std::max(peak, held);
    INFO("frame " << frame << ": " << held << " bytes of pass memory held, " << perFrame << " per frame");
    // Still counted: the objects were retired, not freed, while the frame may be running.
    REQUIRE(held >= perFrame);
    // Bounded: only the frames in flight (and the one just recorded) are held, however many frames ran.
    REQUIRE(held <= (framesInFlight + 1) * perFrame);
  }
  REQUIRE(perFrame > 0);
  CHECK(peak <= (framesInFlight + 1) * perFrame);

  REQUIRE(fx.device().waitIdle().ok());
  fx.ctx().releaseAfterIdle();
  const rb::MemoryStats end = fx.ctx().memoryStats();
  for (size_t c = 0; c < size_t(rb::MemoryCategory::Count); ++c) {
    INFO(rb::toString(rb::MemoryCategory(c)));
    CHECK(end.bytes[c] == start.bytes[c]);
  }
  CHECK(end.allocations == start.allocations);
  destroyScene(fx, built);
}

TEST_CASE("effects front ends created and destroyed every frame, cycling all presets, leak nothing and never wait",
          "[lifetime][hybrid_effects]") {
  GpuFixture fx;
  const uint32_t framesInFlight = fx.ctx().framesInFlight();
  const uint32_t frames = 100;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(48, 32));
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);
  REQUIRE(fx.device().waitIdle().ok());
  fx.ctx().releaseAfterIdle();
  const rb::MemoryStats start = fx.ctx().memoryStats();

  rb::HybridFrame frame;
  frame.gbuffer = gbuffer.desc();
  frame.instances = built.instances;  // the front end records the service's pending work and builds the TLAS
  frame.light.direction[0] = 0.4f;
  frame.light.direction[1] = 1.0f;
  frame.light.direction[2] = 0.3f;
  const rb::Material material;  // reflection hits need a material table

  FrameRing ring(fx, framesInFlight);
  // Steady state: every frame slot has built a TLAS with and without shading records (reflection presets), so the
  // service's per-slot TLAS buffers stop growing.
  rb::MemoryStats steady;
  VkDeviceSize peak = 0;
  for (uint32_t f = 0; f < frames; ++f) {
    const uint32_t slot = f % framesInFlight;
    VkCommandBuffer cmd = ring.acquire(slot);
    fx.ctx().beginFrame();
    const rb::Preset preset = rb::Preset(f % rb::kPresetCount);
    {
      auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), rb::withPreset({}, preset));
      RB_REQUIRE_OK(effects);
      RB_REQUIRE_OK(effects.value()->setMaterials({&material, 1}, {}));
      RB_REQUIRE_OK(effects.value()->record(cmd, frame));
      const rb::PresetDesc want = rb::presetDesc(preset);
      const rb::HybridOutputs& out = effects.value()->outputs();
      INFO("frame " << f << " preset " << rb::toString(preset));
      // Exactly the preset's effects produce images of the frame's size, the others name the 1x1 neutral ones;
      // soft shadows also a denoised one besides the raw.
      CHECK((out.shadowRaw.width == 48) == bool(want.effects & rb::kEffectShadows));
      CHECK((out.ao.width == 48) == bool(want.effects & rb::kEffectAo));
      CHECK((out.reflection.width == 48) == bool(want.effects & rb::kEffectReflections));
      CHECK((out.shadow.view != out.shadowRaw.view) == (want.shadowRaysPerPixel > 1));
      CHECK((effects.value()->shadowDenoiser() != nullptr) == (want.shadowRaysPerPixel > 1));
      for (const rb::EffectImage* image : {&out.shadow, &out.ao, &out.reflection}) {
        CHECK(image->view != VK_NULL_HANDLE);
        CHECK(image->layout == VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
        CHECK((image->width == 48 || image->width == 1));
      }
      ring.submit(slot);
    }  // destroyed while its frame is in flight
    if (f + 1 == 2 * rb::kPresetCount) steady = fx.ctx().memoryStats();
    peak = std::max(peak, passBytes(fx.ctx().memoryStats()) - passBytes(start));
  }
  REQUIRE(peak > 0);
  // memoryByEffect's owner ids are given out again once what they counted is freed: 5 per front end alive or with
  // memory still in flight, not 5 per front end ever created.
  const size_t owners = rb::internal::contextImpl(fx.ctx()).ownerMemory.size();
  INFO(owners << " memory owner ids after " << frames << " front ends");
  CHECK(owners <= 5 * (framesInFlight + 2));

  REQUIRE(fx.device().waitIdle().ok());
  fx.ctx().releaseAfterIdle();
  const rb::MemoryStats end = fx.ctx().memoryStats();
  CHECK(passBytes(end) == passBytes(start));  // every pass, denoiser and shader table of 100 front ends freed
  using C = rb::MemoryCategory;
  for (C c : {C::BlasStorage, C::Scratch, C::Tlas}) {
    INFO(rb::toString(c));
    CHECK(end.of(c) == steady.of(c));  // the service's per-slot TLAS buffers are reused, not regrown
  }
  destroyScene(fx, built);
}

// The primary shading pass the same way, over fewer frames: its pipeline takes seconds to compile on lavapipe.
TEST_CASE("primary shading passes destroyed while their frame is in flight are released by the context",
          "[lifetime][primary-shading]") {
  GpuFixture fx;
  const uint32_t framesInFlight = fx.ctx().framesInFlight();
  TestScene scene = makeConformanceScene();
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  rb::TlasBuildOptions options;
  options.writeShadingRecords = true;  // its hits read them
  BuiltScene built = buildScene(fx, *service.value(), scene, options);
  const rb::PrimaryRayCamera camera = conformanceCamera();
  REQUIRE(fx.device().waitIdle().ok());
  fx.ctx().releaseAfterIdle();
  const rb::MemoryStats start = fx.ctx().memoryStats();

  FrameRing ring(fx, framesInFlight);
  VkDeviceSize perFrame = 0;
  for (uint32_t frame = 0; frame < framesInFlight + 1; ++frame) {
    const uint32_t slot = frame % framesInFlight;
    VkCommandBuffer cmd = ring.acquire(slot);
    fx.ctx().beginFrame();
    {
      auto pass = rb::PrimaryShadingPass::create(fx.ctx());
      RB_REQUIRE_OK(pass);
      RB_REQUIRE_OK(
          pass.value()->record(cmd, {.tlas = built.tlas, .camera = camera, .targets = {48, 32, VK_NULL_HANDLE}}));
      ring.submit(slot);
      if (frame == 0) perFrame = passBytes(fx.ctx().memoryStats()) - passBytes(start);
    }  // destroyed before the GPU has finished the frame, with no wait
    const VkDeviceSize held = passBytes(fx.ctx().memoryStats()) - passBytes(start);
    INFO("frame " << frame << ": " << held << " bytes held, " << perFrame << " per frame");
    REQUIRE(held >= perFrame);  // retired, not freed, while the frame may run
    REQUIRE(held <= (framesInFlight + 1) * perFrame);
  }
  REQUIRE(perFrame > 0);
  REQUIRE(fx.device().waitIdle().ok());
  fx.ctx().releaseAfterIdle();
  const rb::MemoryStats end = fx.ctx().memoryStats();
  for (size_t c = 0; c < size_t(rb::MemoryCategory::Count); ++c) {
    INFO(rb::toString(rb::MemoryCategory(c)));
    CHECK(end.bytes[c] == start.bytes[c]);
  }
  CHECK(end.allocations == start.allocations);
  destroyScene(fx, built);
}
