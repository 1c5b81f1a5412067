// DenoiserScratch (issue 30: transient images aliased across denoisers): denoisers that share one give the images of
// denoisers with their own, bit for bit, over frames of a moving camera, while holding one set of transient images
// instead of one each. HybridEffects shares one among its denoisers; tools/tests/preset_hash_test.cpp checks that
// every preset's images stayed those recorded before the sharing.
#include <catch2/catch_test_macros.hpp>

#include <cstdio>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

// The motion tests' camera, slid sideways by `shift`.
SyntheticView viewAt(double shift) {
  SyntheticView v = motionTestView(96, 72);
  v.eye.x += shift;
  v.target.x += shift;
  return v;
}

// Two AO passes (ranges 0.5 and 2: different signals), each denoised twice in the same frames (the noise of a pass
// follows the frame index): by a denoiser with its own scratch and by one of a pair that shares a DenoiserScratch.
// The far signal's denoisers take 3 a-trous steps, so they use the scratch's second image too. Four frames of a
// sliding camera.
struct Pair {
  std::unique_ptr<rb::Denoiser> near, far;
};

Pair makePair(GpuFixture& fx) {
  auto near = rb::Denoiser::create(fx.ctx());
  auto far = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(near);
  RB_REQUIRE_OK(far);
  return {std::move(near.value()), std::move(far.value())};
}

}  // namespace

TEST_CASE("denoisers sharing a DenoiserScratch give their own scratch's images, bit for bit", "[denoise][memory]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  auto aoNear = rb::AoPass::create(fx.ctx());
  auto aoFar = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(aoNear);
  RB_REQUIRE_OK(aoFar);
  Pair own = makePair(fx), sharing = makePair(fx);
  const VkDeviceSize pixels = 96 * 72;
  rb::AoSettings near, far;
  near.raysPerPixel = far.raysPerPixel = 2;
  near.range = 0.5f;
  far.range = 2.0f;
  rb::DenoiseSettings twoSteps, threeSteps;
  twoSteps.spatialIterations = 2;
  threeSteps.spatialIterations = 3;
  auto scratch = rb::DenoiserScratch::create(fx.ctx());
  RB_REQUIRE_OK(scratch);
  rb::DenoiserScratch* s = scratch.value().get();
  auto passImages = [&] {
    (void)fx.device().waitIdle();
    fx.ctx().releaseAfterIdle();
    return fx.ctx().memoryStats().of(rb::MemoryCategory::PassImages);
  };
  size_t differ = 0, distinct = 0;
  VkDeviceSize ownScratchBytes = 0, sharedScratchBytes = 0;
  for (int frame = 0; frame < 4; ++frame) {
    GpuGBuffer gbuffer(fx, traceGBuffer(embree, viewAt(0.05 * frame)));
    const rb::GBufferDesc g = gbuffer.desc();
    const VkDeviceSize before = passImages();
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto tlas = service.value()->recordTlasBuild(cmd, built.instances, gbuffer.cameraRelativeTlas());
      RB_REQUIRE_OK(tlas);
      RB_REQUIRE_OK(aoNear.value()->record(cmd, {.gbuffer = g, .tlas = tlas.value(), .settings = near}));
      RB_REQUIRE_OK(aoFar.value()->record(cmd, {.gbuffer = g, .tlas = tlas.value(), .settings = far}));
      const VkImageView nearSignal = aoNear.value()->outputs().aoView, farSignal = aoFar.value()->outputs().aoView;
      RB_REQUIRE_OK(own.near->record(cmd, {.gbuffer = g, .signal = nearSignal, .settings = twoSteps}));
      RB_REQUIRE_OK(
          sharing.near->record(cmd, {.gbuffer = g, .signal = nearSignal, .settings = twoSteps, .scratch = s}));
      RB_REQUIRE_OK(own.far->record(cmd, {.gbuffer = g, .signal = farSignal, .settings = threeSteps}));
      RB_REQUIRE_OK(
          sharing.far->record(cmd, {.gbuffer = g, .signal = farSignal, .settings = threeSteps, .scratch = s}));
    });
    if (frame == 0) {
      // The first frame created every image; the shared scratch counts to nobody but the Context.
      const VkDeviceSize perDenoiser = 18 * pixels;  // a scalar denoiser's own history, distance, temporal, output
      const VkDeviceSize grown = passImages() - before - 2 * 2 * pixels;  // less the two AO outputs (R16F)
      ownScratchBytes = 4 * pixels + 8 * pixels;  // its ping for the near one, ping and pong for the far one
      sharedScratchBytes = 8 * pixels;
      CHECK(grown == 4 * perDenoiser + ownScratchBytes + sharedScratchBytes);
    }
    const auto read = [&](const rb::Denoiser& d) { return readR16f(fx, d.outputs().denoised, g.width, g.height); };
    const std::vector<float> a = read(*own.near), b = read(*sharing.near), c = read(*own.far), d = read(*sharing.far);
    for (size_t i = 0; i < a.size(); ++i) {
      differ += a[i] != b[i] || c[i] != d[i];
      distinct += a[i] != c[i];
    }
  }
  std::printf("[denoise][memory] 4 frames: %zu pixels differ between own and shared scratch; the two signals differ in "
              "%zu; transient images %llu B own, %llu B shared\n",
              differ, distinct, static_cast<unsigned long long>(ownScratchBytes),
              static_cast<unsigned long long>(sharedScratchBytes));
  CHECK(differ == 0);
  CHECK(distinct > 1000);  // two different signals went through the shared images
  own = {};
  sharing = {};
  scratch.value().reset();
  aoNear.value().reset();
  aoFar.value().reset();
  (void)fx.device().waitIdle();
  destroyScene(fx, built);
}
