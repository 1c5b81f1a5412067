// Failure injection (issue 12, item 5): the SDK's Vulkan calls fail one at a time, through a wrapping
// vkGetInstanceProcAddr (failure_injection.h; the SDK has no test hook), while an engine's life with the SDK plays
// out on a lavapipe device of its own: an AccelerationStructureService with static meshes and a deforming one, or
// HybridEffects with one effect at Ultra's settings (shadows with the tile classifier and adaptive rays, AO with
// adaptive rays, reflections, local lights), denoised; three or more frames; destruction. Every allocation site of
// a clean run fails once: the SDK call that made the failing Vulkan call must return an error naming it; the run
// carries on as an engine would (destroys and creates again, or records the next frame) and must then work in every
// frame slot; at the end no memory, no Vulkan object and no validation message may be left.
// Lost devices: the reads of query results (passes, denoisers, BLAS builds), the async queue's submission and
// timeline.
#include <catch2/catch_test_macros.hpp>

#include <chrono>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "async_submitter.h"
#include "failure_injection.h"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

constexpr uint32_t kWidth = 32, kHeight = 24;
// Both frame slots, then the first again with more TLAS instances (its buffers grow); adaptive rays from the second
// frame on. After an error, frames go on until every frame slot has recorded cleanly again (at most kExtraFrames).
constexpr uint32_t kFrames = 3;
constexpr uint32_t kExtraFrames = 4;
constexpr uint32_t kFramesInFlight = 2;  // the fixture's

// An error an SDK call returned, with the allocation calls it made (the injector's count before and after it).
struct SdkError {
  std::string call;
  rb::Error error;
  uint64_t callsBefore = 0, callsAfter = 0;
};

struct Run {
  std::vector<SdkError> errors;
  uint32_t frames = 0;         // recorded
  uint32_t cleanFrames = 0;    // frames recorded without an error since the last error
  uint32_t unbuiltMeshes = 0;  // registered meshes whose BLAS was not built by the end
  rb::AsStats asStats;
  rb::HybridStats fxStats;
  rb::MemoryStats end;
  std::vector<std::string> live, misuse, validation;
};

double seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

bool isZero(const rb::MemoryStats& m) { return m.total() == 0 && m.allocations == 0; }

std::string describe(const rb::MemoryStats& m) {
  std::string s = std::to_string(m.allocations) + " allocations;";
  for (uint32_t c = 0; c < uint32_t(rb::MemoryCategory::Count); ++c) {
    s += std::string(" ") + rb::toString(rb::MemoryCategory(c)) + " " + std::to_string(m.bytes[c]);
  }
  return s;
}

// What a run exercises. Each effect has a scenario of its own (the runs of one recreate its pipelines, which takes
// most of a run's time on a CPU device, so all effects in one scenario would take minutes longer for the same sites).
struct Variant {
  const char* name;
  rb::EffectSet effects;  // 0: the engine records the service's work and its TLAS itself, no effects
  // The effects front end records the injected service's work and builds the TLAS; else the frames bring a TLAS
  // made on the fixture's own context.
  bool effectsBuildTlas;
};

// The engine's side of a run: its mesh buffers, the G-buffer and a TLAS over the scene, all made through the
// fixture's own context, which the injector never sees.
class Scenario {
 public:
  explicit Scenario(GpuFixture& fx) : fx_(fx) {
    scene_.meshes.push_back(rbsamples::makeGrid(12.0f, 4));
    scene_.meshes.push_back(rbsamples::makeSphere(1.0f, 12, 6));
    const float mn[3] = {-1, -1, -1}, mx[3] = {1, 1, 1};
    scene_.meshes.push_back(rbsamples::makeBox(mn, mx));
    scene_.instances.push_back({0, translation(0, 0, 0)});
    scene_.instances.push_back({1, translation(-2.0f, 1.0f, 0)});
    scene_.instances.push_back({2, translation(1.5f, 1.0f, -1.0f)});
    dynamic_ = fx.upload(rbsamples::makeSphere(0.7f, 10, 5));
    dynamic_.desc.role = rb::MeshRole::Dynamic;
    dynamic_.desc.debugName = "deforming sphere";
    EmbreeScene embree;
    addToEmbree(embree, scene_);
    SyntheticView view;
    view.eye = {-5.0, 4.0, 7.0};
    view.target = {0.0, 0.8, 0.0};
    view.width = kWidth;
    view.height = kHeight;
    gbuffer_ = std::make_unique<GpuGBuffer>(fx, traceGBuffer(embree, view, {0.3f, 0.0f, 0.6f}));
    auto service = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(service);
    engineService_ = std::move(service.value());
    engineScene_ = buildScene(fx, *engineService_, scene_, gbuffer_->cameraRelativeTlas(true));

    for (int i = 0; i < 3; ++i) {
      rb::LightSource l;
      l.light.type = rb::LightType::Point;
      l.light.position[0] = -3.0 + 3.0 * i;
      l.light.position[1] = 2.5;
      l.light.position[2] = 1.0;
      l.light.radius = 0.2f;
      l.intensity = 5.0f;
      lights_.push_back(l);
    }
  }
  ~Scenario() {
    (void)fx_.device().waitIdle();
    destroyScene(fx_, engineScene_);
    engineService_.reset();
    fx_.destroy(dynamic_);
  }

  // Ultra's settings of every effect, local lights stochastic, the shadow tile classifier and adaptive rays on.
  static rb::HybridEffectsDesc effectsDesc(rb::EffectSet effects) {
    rb::HybridEffectsDesc d = rb::withPreset({}, rb::Preset::Ultra);
    d.effects = effects;
    d.shadows.schedule.tileClassifier = true;
    d.shadows.schedule.adaptive.enabled = true;
    d.ao.schedule.adaptive.enabled = true;
    d.ao.range = 2.0f;
    return d;
  }

  // One engine's life with the SDK on a context made from `inject` (configured by the caller).
  Run run(FailureInjector& inject, const Variant& variant) {
    Run run;
    const uint32_t validationBefore = fx_.device().validationErrorCount();
    // Every SDK call goes through here: an error is kept with the allocation calls the SDK call made.
    auto guarded = [&](const std::string& call, auto&& sdkCall) {
      const uint64_t before = inject.calls();
      auto result = sdkCall();
      if (!result.ok()) run.errors.push_back({call, result.error(), before, inject.calls()});
      return result.ok();
    };

    auto context = rb::Context::create(inject.wrap(fx_.device().contextDesc()));
    RB_REQUIRE_OK(context);
    rb::Context& ctx = *context.value();
    REQUIRE(ctx.framesInFlight() == kFramesInFlight);

    // The scene on the injected service: the static meshes share the engine's buffers, plus a deforming mesh.
    const bool ownService = variant.effects == 0 || variant.effectsBuildTlas;
    std::unique_ptr<rb::AccelerationStructureService> service;
    rb::MeshHandle character;
    std::vector<rb::Instance> instances;
    if (ownService) {
      rb::AsServiceDesc asDesc;
      asDesc.storageBlockBytes = 64 << 10;   // several storage blocks
      asDesc.scratchBudgetBytes = 64 << 10;  // several build batches, and a BLAS with scratch of its own
      for (int attempt = 0; attempt < 2 && !service; ++attempt) {
        guarded("AccelerationStructureService::create", [&] {
          auto s = rb::AccelerationStructureService::create(ctx, asDesc);
          if (s) service = std::move(s.value());
          return s ? rb::Status() : rb::Status(s.error());
        });
      }
      REQUIRE(service);
      std::vector<rb::MeshHandle> handles;
      for (const UploadedMesh& u : engineScene_.uploads) {
        auto h = service->registerMesh(u.desc);
        RB_REQUIRE_OK(h);
        handles.push_back(h.value());
      }
      auto h = service->registerMesh(dynamic_.desc);
      RB_REQUIRE_OK(h);
      character = h.value();
      for (const SceneInstance& si : scene_.instances) {
        rb::Instance inst;
        inst.mesh = handles[si.mesh];
        std::copy(si.transform.begin(), si.transform.end(), inst.transform);
        instances.push_back(inst);
      }
      rb::Instance c;
      c.mesh = character;
      const auto at = translation(0.0f, 1.0f, 2.0f);
      std::copy(at.begin(), at.end(), c.transform);
      instances.push_back(c);
    }

    std::unique_ptr<rb::HybridEffects> effects;
    if (variant.effects) {
      for (int attempt = 0; attempt < 2 && !effects; ++attempt) {
        guarded("HybridEffects::create", [&] {
          auto e = rb::HybridEffects::create(ctx, service.get(), effectsDesc(variant.effects));
          if (e) effects = std::move(e.value());
          return e ? rb::Status() : rb::Status(e.error());
        });
      }
      REQUIRE(effects);
      const rb::Material material;
      for (int attempt = 0; attempt < 2; ++attempt) {
        if (guarded("HybridEffects::setMaterials", [&] { return effects->setMaterials({&material, 1}, {}); })) break;
      }
    }

    rb::HybridFrame frame;
    frame.gbuffer = gbuffer_->desc();
    if (variant.effectsBuildTlas) {
      frame.instances = instances;
    } else {
      frame.tlas = &engineScene_.tlas;
    }
    frame.light.direction[0] = 0.4f;
    frame.light.direction[1] = 1.0f;
    frame.light.direction[2] = 0.3f;
    frame.localLights = lights_;
    // Frames from the third on trace the scene 20 times over: the TLAS of a frame slot outgrows its buffers.
    std::vector<rb::Instance> crowd;
    for (int copy = 0; copy < 20; ++copy) {
      for (rb::Instance inst : instances) {
        inst.transform[3] += 30.0f * float(copy);
        crowd.push_back(inst);
      }
    }
    for (uint32_t f = 0; f < kFrames || (run.cleanFrames < kFramesInFlight && f < kFrames + kExtraFrames); ++f) {
      ctx.beginFrame();
      auto cmd = fx_.device().beginCommands();
      RB_REQUIRE_OK(cmd);
      const size_t errorsBefore = run.errors.size();
      const std::string n = " (frame " + std::to_string(f) + ")";
      if (service) guarded("updateMesh" + n, [&] { return service->updateMesh(character); });
      if (effects) {
        guarded("HybridEffects::record" + n, [&] { return effects->record(cmd.value(), frame); });
      } else if (guarded("recordPendingWork" + n, [&] { return service->recordPendingWork(cmd.value()); })) {
        // Every TLAS path: read in place, then a refit with device copies and shading records.
        rb::TlasBuildOptions options = gbuffer_->cameraRelativeTlas(f > 0);
        options.mode = f > 0 ? rb::TlasBuildMode::UpdateIfPossible : rb::TlasBuildMode::Rebuild;
        options.instanceUpload = f > 0 ? rb::TlasInstanceUpload::CopyToDevice : rb::TlasInstanceUpload::ReadInPlace;
        std::span<const rb::Instance> list = f >= 2 ? std::span<const rb::Instance>(crowd) : instances;
        guarded("recordTlasBuild" + n, [&] { return service->recordTlasBuild(cmd.value(), list, options); });
      }
      // Whatever was recorded before an error must be a valid command buffer.
      RB_REQUIRE_OK(fx_.device().submitAndWait(cmd.value()));
      if (service) run.asStats = service->stats();
      if (effects) run.fxStats = effects->stats();
      run.cleanFrames = run.errors.size() == errorsBefore ? run.cleanFrames + 1 : 0;
      ++run.frames;
    }

    if (service) {
      for (const rb::Instance& inst : instances) {
        auto built = service->isBuilt(inst.mesh);
        run.unbuiltMeshes += !built || !built.value();
      }
    }

    // The engine's shutdown: the GPU is idle, then the SDK objects go in reverse order of creation.
    REQUIRE(fx_.device().waitIdle().ok());
    effects.reset();
    if (service) RB_REQUIRE_OK(service->releaseMesh(character));
    service.reset();
    ctx.releaseAfterIdle();
    run.end = ctx.memoryStats();
    context.value().reset();
    run.live = inject.liveObjects();
    run.misuse = inject.misuse();
    const std::vector<std::string>& all = fx_.device().validationErrors();
    run.validation.assign(all.begin() + validationBefore, all.end());
    return run;
  }

 private:
  GpuFixture& fx_;
  TestScene scene_;
  UploadedMesh dynamic_;
  std::unique_ptr<GpuGBuffer> gbuffer_;
  std::unique_ptr<rb::AccelerationStructureService> engineService_;
  BuiltScene engineScene_;
  std::vector<rb::LightSource> lights_;
};

void checkClean(const Run& run) {
  INFO("memory at the end: " << describe(run.end));
  CHECK(isZero(run.end));
  for (const std::string& l : run.live) UNSCOPED_INFO("leaked: " << l);
  CHECK(run.live.empty());
  for (const std::string& m : run.misuse) UNSCOPED_INFO("misuse: " << m);
  CHECK(run.misuse.empty());
  for (const std::string& v : run.validation) UNSCOPED_INFO("validation: " << v);
  CHECK(run.validation.empty());
}

// One engine's life with the SDK, on a device of its own: the injector is configured by `plan`.
struct DeviceRun {
  Run run;
  std::vector<std::string> sites;  // the allocation calls, in order
  std::vector<InjectedFailure> failures;
  uint64_t queryReads = 0;  // vkGetQueryPoolResults calls
};

// A device per run: a Vulkan object an error path leaks is a validation error at vkDestroyDevice, whatever the
// wrappers saw; and on one device used for hundreds of runs, lavapipe came to compile every pipeline of each run again
// (Mesa's shader cache no longer matched: seconds per run, 87% of the time in LLVM), which a new device does not.
DeviceRun runOnDevice(const Variant& variant, const std::function<void(FailureInjector&)>& plan) {
  auto fx = std::make_unique<GpuFixture>();
  DeviceRun out;
  {
    FailureInjector inject(fx->device().getInstanceProcAddr());
    Scenario scenario(*fx);
    inject.reset();
    plan(inject);
    out.run = scenario.run(inject, variant);
    out.sites = inject.callLog();
    out.failures = inject.failures();
    out.queryReads = inject.callsOf("vkGetQueryPoolResults");
  }
  fx.reset();  // destroys the device: the validation layer reports any object left behind (a test failure)
  return out;
}

}  // namespace

TEST_CASE("every allocation site of the SDK fails in turn: named errors, recovery, nothing leaked", "[inject]") {
  const Variant variants[] = {
      {"acceleration structures", 0, false},
      {"shadows", rb::kEffectShadows, false},
      {"ambient occlusion", rb::kEffectAo, false},
      {"reflections", rb::kEffectReflections, false},
      {"local lights, TLAS built by the front end", rb::kEffectLocalLights, true},
  };
  const auto start = std::chrono::steady_clock::now();
  std::map<std::string, uint32_t> sitesOf, survivedOf;
  uint64_t total = 0;
  for (const Variant& variant : variants) {
    INFO("scenario: " << variant.name);
    // Without failures: the sites, in call order.
    const auto begin = std::chrono::steady_clock::now();
    const DeviceRun clean = runOnDevice(variant, [](FailureInjector&) {});
    for (const SdkError& e : clean.run.errors) UNSCOPED_INFO(e.call << ": " << e.error.message);
    REQUIRE(clean.run.errors.empty());
    REQUIRE(clean.run.cleanFrames == kFrames);
    CHECK(clean.run.unbuiltMeshes == 0);
    checkClean(clean.run);
    if (variant.effects) CHECK(clean.run.fxStats.totalRays() > 0);
    const std::vector<std::string>& sites = clean.sites;
    const uint64_t n = sites.size();
    REQUIRE(n > 0);
    for (const std::string& site : sites) ++sitesOf[site];
    total += n;

    for (uint64_t k = 1; k <= n; ++k) {
      INFO("allocation call " << k << " of " << n << ": " << sites[k - 1]);
      const DeviceRun failing = runOnDevice(variant, [k](FailureInjector& inject) { inject.failCall(k); });
      const Run& run = failing.run;
      REQUIRE(failing.failures.size() == 1);
      const InjectedFailure& failure = failing.failures[0];
      CHECK(failure.function == sites[k - 1]);
      for (const SdkError& e : run.errors) UNSCOPED_INFO("error from " << e.call << ": " << e.error.message);
      // (a) The SDK call that made the failing Vulkan call returned the error, naming that call and its result;
      // no other call failed because of it.
      REQUIRE(run.errors.size() == 1);
      const SdkError& e = run.errors[0];
      CHECK(e.callsBefore < k);
      CHECK(k <= e.callsAfter);
      CHECK(e.error.code == rb::ErrorCode::VulkanError);
      CHECK(e.error.vkResult == failure.result);
      CHECK(e.error.message.find(failure.function) != std::string::npos);
      CHECK(e.error.message.find(rb::toString(failure.result)) != std::string::npos);
      // (b) The engine carried on (destroyed what failed to be created and made it again, or recorded the next
      // frame) and the SDK worked again: the last frame of every slot recorded cleanly, with every mesh built.
      CHECK(run.cleanFrames >= kFramesInFlight);
      CHECK(run.unbuiltMeshes == 0);
      // (c), (d) Nothing left: memory, Vulkan objects, validation messages.
      checkClean(run);
      ++survivedOf[failure.function];
    }
    std::printf("[inject] %-42s %4llu allocation sites, %.1f s\n", variant.name, static_cast<unsigned long long>(n),
                seconds(begin));
  }
  std::printf("[inject] %llu allocation sites in all, each failed once, %.1f s:\n",
              static_cast<unsigned long long>(total), seconds(start));
  for (const auto& [function, count] : sitesOf) {
    std::printf("[inject]   %-38s %4u sites, %4u survived\n", function.c_str(), count, survivedOf[function]);
  }
}

TEST_CASE("a device lost while reading query results is reported, and destruction stays clean",
          "[inject][device-lost]") {
  // Every effect; the TLAS from the engine (the passes and denoisers read their timestamps), then from the front end
  // (the service reads its build timings and compacted sizes first).
  for (const Variant& variant : {Variant{"every effect", rb::kAllEffects, false},
                                 Variant{"every effect, TLAS built by the front end", rb::kAllEffects, true}}) {
    INFO("scenario: " << variant.name);
    const DeviceRun lost = runOnDevice(variant,
                                       [](FailureInjector& inject) { inject.loseDevice("vkGetQueryPoolResults"); });
    const Run& run = lost.run;
    REQUIRE(lost.queryReads > 0);
    // The recording calls report it, naming the read; the statistics hold no garbage.
    REQUIRE_FALSE(run.errors.empty());
    for (const SdkError& e : run.errors) {
      INFO(e.call << ": " << e.error.message);
      CHECK(e.error.vkResult == VK_ERROR_DEVICE_LOST);
      CHECK(e.error.message.find("vkGetQueryPoolResults") != std::string::npos);
      CHECK(e.error.message.find("VK_ERROR_DEVICE_LOST") != std::string::npos);
    }
    CHECK(run.asStats.batches.empty());
    CHECK(run.fxStats.totalGpuMs() == 0.0);
    checkClean(run);
  }
}

TEST_CASE("a device lost on the async BLAS queue is reported by its submission and its timeline",
          "[inject][device-lost]") {
  // The SDK's submitter on the fixture's queue (lavapipe has no second family; the submitter does not care).
  GpuFixture fx;
  FailureInjector inject(fx.device().getInstanceProcAddr());
  inject.reset();
  auto context = rb::Context::create(inject.wrap(fx.device().contextDesc()));
  RB_REQUIRE_OK(context);
  rb::Context::Impl& c = rb::internal::contextImpl(*context.value());
  // Its creation fails at each of its two objects in turn (the async modes never run on lavapipe, so the sweep of
  // allocation sites does not reach it).
  for (uint64_t k : {1u, 2u}) {
    inject.reset();
    inject.failCall(k);
    rb::AsyncSubmitter failing;
    const rb::Status s = failing.create(c, fx.device().queue(), fx.device().queueFamily());
    REQUIRE(inject.failures().size() == 1);
    INFO(s.error().message);
    REQUIRE_FALSE(s.ok());
    CHECK(s.error().message.find(inject.failures()[0].function) != std::string::npos);
    failing.destroy();
    CHECK(inject.misuse().empty());
    CHECK(inject.liveObjects().empty());
  }
  inject.reset();
  rb::AsyncSubmitter submitter;
  RB_REQUIRE_OK(submitter.create(c, fx.device().queue(), fx.device().queueFamily()));

  // A submission that works, then one whose vkQueueSubmit reports the lost device.
  auto cmd = submitter.begin();
  RB_REQUIRE_OK(cmd);
  auto value = submitter.submit(cmd.value(), {}, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT);
  RB_REQUIRE_OK(value);
  CHECK(value.value() == 1);
  REQUIRE(fx.device().waitIdle().ok());
  CHECK(submitter.completedValue() == 1);
  inject.loseDevice("vkQueueSubmit", inject.callsOf("vkQueueSubmit") + 1);
  cmd = submitter.begin();
  RB_REQUIRE_OK(cmd);
  value = submitter.submit(cmd.value(), {}, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT);
  REQUIRE_FALSE(value.ok());
  INFO(value.error().message);
  CHECK(value.error().vkResult == VK_ERROR_DEVICE_LOST);
  CHECK(value.error().message.find("vkQueueSubmit") != std::string::npos);
  CHECK(value.error().message.find("VK_ERROR_DEVICE_LOST") != std::string::npos);
  CHECK(submitter.lastSubmitted() == 1);  // nothing was submitted: no value to wait for

  // The timeline reports it too: the next command buffer is refused, and the known value stays.
  inject.loseDevice("vkGetSemaphoreCounterValue", inject.callsOf("vkGetSemaphoreCounterValue") + 1);
  cmd = submitter.begin();
  REQUIRE_FALSE(cmd.ok());
  INFO(cmd.error().message);
  CHECK(cmd.error().vkResult == VK_ERROR_DEVICE_LOST);
  CHECK(cmd.error().message.find("vkGetSemaphoreCounterValue") != std::string::npos);
  CHECK(submitter.completedValue() == 1);

  submitter.destroy();
  context.value().reset();
  for (const std::string& l : inject.liveObjects()) UNSCOPED_INFO("leaked: " << l);
  CHECK(inject.liveObjects().empty());
  CHECK(inject.misuse().empty());
}
