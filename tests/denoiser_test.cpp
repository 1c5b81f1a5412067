// The denoiser: 4-ray AO denoised beats raw 4-ray AO and is no worse than raw 16-ray AO against a converged
// reference; temporal accumulation with reprojection keeps improving while the camera moves.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <cmath>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

struct AoScene {
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  AoScene() { addToEmbree(embree, scene); }
};

SyntheticView viewAt(double shift) {
  SyntheticView v;
  v.eye = {-6.0 + shift, 3.5, 7.0};
  v.target = {0.0 + shift, 0.8, 0.0};
  v.fovYDegrees = 45.0;
  v.width = 96;
  v.height = 72;
  return v;
}

// Runs `frames` frames of AO (and the denoiser when `denoise`) over the views given, returns the last output.
std::vector<float> runFrames(GpuFixture& fx, const AoScene& s, const std::vector<CpuGBuffer>& views, uint32_t rays,
                             bool denoise, const rb::DenoiseSettings& dn = {}) {
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto denoiser = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(denoiser);
  BuiltScene built = buildScene(fx, *service.value(), s.scene);
  rb::AoSettings settings;
  settings.raysPerPixel = rays;
  settings.range = 2.0f;
  std::vector<float> out;
  for (const CpuGBuffer& cpu : views) {
    GpuGBuffer gbuffer(fx, cpu);
    rb::GBufferDesc desc = gbuffer.desc();
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto tlas = service.value()->recordTlasBuild(cmd, built.instances, gbuffer.cameraRelativeTlas());
      RB_REQUIRE_OK(tlas);
      RB_REQUIRE_OK(ao.value()->record(cmd, desc, tlas.value(), settings));
      if (denoise) RB_REQUIRE_OK(denoiser.value()->record(cmd, desc, ao.value()->outputs().aoView, dn));
    });
    VkImage image = denoise ? denoiser.value()->outputs().denoised : ao.value()->outputs().ao;
    out = readR16f(fx, image, desc.width, desc.height);
  }
  (void)fx.device().waitIdle();
  destroyScene(fx, built);
  return out;
}

double rmse(const std::vector<float>& a, const std::vector<float>& b, const CpuGBuffer& g) {
  double sum = 0.0;
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!g.hit[i]) continue;
    sum += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    ++n;
  }
  return std::sqrt(sum / double(n));
}

}  // namespace

TEST_CASE("denoised 4-ray AO beats raw 4-ray AO and matches raw 16-ray AO", "[denoise][ao]") {
  GpuFixture fx;
  AoScene s;
  CpuGBuffer g = traceGBuffer(s.embree, viewAt(0.0));
  std::vector<float> reference = runFrames(fx, s, {g}, 2048, false);
  std::vector<float> raw4 = runFrames(fx, s, {g}, 4, false);
  std::vector<float> raw16 = runFrames(fx, s, {g}, 16, false);
  rb::DenoiseSettings spatialOnly;
  spatialOnly.disableTemporal = true;
  std::vector<float> denoised4 = runFrames(fx, s, {g}, 4, true, spatialOnly);
  double eRaw4 = rmse(raw4, reference, g), eRaw16 = rmse(raw16, reference, g),
         eDenoised = rmse(denoised4, reference, g);
  INFO("RMSE raw 4: " << eRaw4 << ", raw 16: " << eRaw16 << ", denoised 4 (one frame, spatial): " << eDenoised);
  CHECK(eDenoised < eRaw4);
  CHECK(eDenoised <= eRaw16);
  // The full denoiser (temporal + spatial) over four frames of a still camera does better still.
  std::vector<float> full = runFrames(fx, s, {g, g, g, g}, 4, true);
  double eFull = rmse(full, reference, g);
  INFO("full denoiser after 4 frames: " << eFull);
  CHECK(eFull < eDenoised);
}

TEST_CASE("temporal accumulation reprojects through camera motion", "[denoise][temporal]") {
  GpuFixture fx;
  AoScene s;
  // Eight frames while the camera pans sideways; the reference is the last frame's converged AO.
  std::vector<CpuGBuffer> views;
  for (int i = 0; i < 8; ++i) views.push_back(traceGBuffer(s.embree, viewAt(0.08 * i)));
  const CpuGBuffer& last = views.back();
  std::vector<float> reference = runFrames(fx, s, {last}, 2048, false);
  rb::DenoiseSettings temporalOnly;
  temporalOnly.disableSpatial = true;
  std::vector<float> accumulated = runFrames(fx, s, views, 4, true, temporalOnly);
  std::vector<float> oneFrame = runFrames(fx, s, {last}, 4, true, temporalOnly);  // nothing to accumulate yet
  double eAcc = rmse(accumulated, reference, last), eOne = rmse(oneFrame, reference, last);
  INFO("RMSE after 8 reprojected frames " << eAcc << ", after 1 frame " << eOne);
  // Eight frames of 4 rays behave like ~32 rays where the history survived: far below one frame's error.
  CHECK(eAcc < 0.6 * eOne);
  // A camera cut: a history that does not match is rejected, not smeared (the result equals one frame's).
  std::vector<CpuGBuffer> cut = {views.front(), traceGBuffer(s.embree, [] {
                                   SyntheticView v = viewAt(0.0);
                                   v.eye = {7.0, 3.0, -6.0};
                                   v.target = {0.0, 0.8, 0.0};
                                   return v;
                                 }())};
  std::vector<float> afterCut = runFrames(fx, s, cut, 4, true, temporalOnly);
  std::vector<float> cutReference = runFrames(fx, s, {cut.back()}, 2048, false);
  std::vector<float> cutOneFrame = runFrames(fx, s, {cut.back()}, 4, true, temporalOnly);
  double eCut = rmse(afterCut, cutReference, cut.back()), eCutOne = rmse(cutOneFrame, cutReference, cut.back());
  INFO("after a camera cut: " << eCut << " vs one fresh frame " << eCutOne);
  CHECK(eCut < 1.3 * eCutOne);
}
