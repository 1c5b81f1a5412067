// The RGB denoiser on the many-light pass's irradiance: against the exact mode, denoised stochastic output is
// well below the raw error after one frame and far below it after sixteen still frames (or eight moving ones); a
// noise-free (exact) input comes through nearly unchanged; colour is kept; a light's hot spot stays where it is;
// and the effects front end denoises its stochastic local lights.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "many_light_scene.h"

using namespace rbtest;

namespace {

// The raw and denoised images of every frame listed in `readAt` (1 = the first frame).
struct DenoisedFrames {
  std::vector<std::vector<float>> raw, denoised;
};

// One frame per view of the many-light pass and, unless `denoise` is false, an RGB denoiser after it. Each
// frame is its own Context frame, so the pass draws new random numbers (its seed follows the frame index).
DenoisedFrames runViews(GpuFixture& fx, const TestScene& scene, const std::vector<CpuGBuffer>& views,
                        const std::vector<rb::LightSource>& lights, const rb::ManyLightSettings& settings,
                        const std::vector<uint32_t>& readAt, bool denoise = true, const rb::DenoiseSettings& dn = {}) {
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto pass = rb::ManyLightPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::DenoiserDesc desc;
  desc.signal = rb::DenoiseSignal::Rgb;
  auto denoiser = rb::Denoiser::create(fx.ctx(), desc);
  RB_REQUIRE_OK(denoiser);
  CHECK(denoiser.value()->signal() == rb::DenoiseSignal::Rgb);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  DenoisedFrames out;
  for (uint32_t f = 1; f <= views.size(); ++f) {
    GpuGBuffer gbuffer(fx, views[f - 1]);
    const rb::GBufferDesc g = gbuffer.desc();
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto tlas = service.value()->recordTlasBuild(cmd, built.instances, gbuffer.cameraRelativeTlas());
      RB_REQUIRE_OK(tlas);
      RB_REQUIRE_OK(
          pass.value()->record(cmd, {.gbuffer = g, .tlas = tlas.value(), .lights = lights, .settings = settings}));
      if (denoise)
        RB_REQUIRE_OK(denoiser.value()->record(
            cmd, {.gbuffer = g, .signal = pass.value()->outputs().irradianceView, .settings = dn}));
    });
    if (std::find(readAt.begin(), readAt.end(), f) == readAt.end()) continue;
    out.raw.push_back(readRgba16f(fx, pass.value()->outputs().irradiance, g.width, g.height));
    if (denoise) {
      const rb::DenoiseOutputs& o = denoiser.value()->outputs();
      REQUIRE(o.width == g.width);
      out.denoised.push_back(readRgba16f(fx, o.denoised, g.width, g.height));
    }
  }
  for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
  (void)fx.device().waitIdle();
  destroyScene(fx, built);
  return out;
}

// `frames` still frames.
DenoisedFrames runFrames(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu,
                         const std::vector<rb::LightSource>& lights, const rb::ManyLightSettings& settings,
                         uint32_t frames, const std::vector<uint32_t>& readAt, bool denoise = true,
                         const rb::DenoiseSettings& dn = {}) {
  return runViews(fx, scene, std::vector<CpuGBuffer>(frames, cpu), lights, settings, readAt, denoise, dn);
}

rb::ManyLightSettings exactMode() {
  rb::ManyLightSettings s;
  s.mode = rb::ManyLightMode::Exact;
  return s;
}

rb::ManyLightSettings stochastic(uint32_t rays) {
  rb::ManyLightSettings s;
  s.raysPerPixel = rays;
  return s;
}

std::vector<uint8_t> surfaceOf(const CpuGBuffer& cpu) { return {cpu.hit.begin(), cpu.hit.end()}; }

struct RoomSetup {
  TestScene scene = makeRoom();
  EmbreeScene embree;
  CpuGBuffer cpu;
  explicit RoomSetup(uint32_t width = 128, uint32_t height = 96) {
    addToEmbree(embree, scene);
    cpu = traceGBuffer(embree, roomView(width, height));
  }
};

}  // namespace

TEST_CASE("RGB denoised 4-ray many-light irradiance is far closer to the exact mode than raw",
          "[many_lights][denoise]") {
  GpuFixture fx;
  RoomSetup room;
  const std::vector<rb::LightSource> lights = manyRoomLights();
  const std::vector<uint8_t> surface = surfaceOf(room.cpu);
  std::vector<float> exact = runFrames(fx, room.scene, room.cpu, lights, exactMode(), 1, {1}, false).raw[0];
  DenoisedFrames run = runFrames(fx, room.scene, room.cpu, lights, stochastic(4), 16, {1, 16});
  const double raw1 = relativeRmse(run.raw[0], exact, surface), raw16 = relativeRmse(run.raw[1], exact, surface);
  const double dn1 = relativeRmse(run.denoised[0], exact, surface);
  const double dn16 = relativeRmse(run.denoised[1], exact, surface);
  std::printf("[many_lights][denoise] 32 lights, 4 rays, 128x96: relative RMSE raw %.4f (frame 16: %.4f), "
              "denoised after 1 frame %.4f, after 16 frames %.4f\n",
              raw1, raw16, dn1, dn16);
  INFO("relative RMSE raw " << raw1 << " (frame 16 " << raw16 << "), denoised 1 frame " << dn1 << ", 16 frames "
                            << dn16);
  CHECK(raw1 > 0.05);  // the input is noisy, or the test would not see a filter that does nothing
  CHECK(std::fabs(raw16 - raw1) < 0.5 * raw1);  // every frame is as noisy as the first: new random numbers
  CHECK(run.raw[0] != run.raw[1]);
  CHECK(dn1 < 0.7 * raw1);
  CHECK(dn16 < 0.2 * raw1);
  CHECK(dn16 < 0.6 * dn1);  // the history keeps helping while the camera is still
  for (float v : run.denoised[1]) REQUIRE(std::isfinite(v));
  // Alpha is 1 on every pixel of the output.
  uint32_t badAlpha = 0;
  for (size_t i = 3; i < run.denoised[1].size(); i += 4) badAlpha += run.denoised[1][i] != 1.0f;
  CHECK(badAlpha == 0);
}

TEST_CASE("RGB denoising leaves a noise-free signal (the exact mode) nearly unchanged", "[many_lights][denoise]") {
  GpuFixture fx;
  RoomSetup room;
  const std::vector<rb::LightSource> lights = manyRoomLights();
  const std::vector<uint8_t> surface = surfaceOf(room.cpu);
  DenoisedFrames run = runFrames(fx, room.scene, room.cpu, lights, exactMode(), 8, {1, 8});
  const double e1 = relativeRmse(run.denoised[0], run.raw[0], surface);
  const double e8 = relativeRmse(run.denoised[1], run.raw[1], surface);
  std::printf("[many_lights][denoise] exact input through the RGB denoiser: relative change %.4f after 1 frame, "
              "%.4f after 8 frames\n",
              e1, e8);
  INFO("relative change after 1 frame " << e1 << ", after 8 frames " << e8);
  CHECK(run.raw[0] == run.raw[1]);  // the exact mode is deterministic
  // One frame has no history: the noise is estimated from the neighbourhood, which mistakes a little of the
  // lighting's curvature for noise. With a history the variance is measured: ~0 here.
  CHECK(e1 <= 0.02);
  CHECK(e8 <= 0.005);
  // Spatial filtering alone (no history, the noise estimated from the neighbourhood) is just as careful.
  rb::DenoiseSettings spatialOnly;
  spatialOnly.disableTemporal = true;
  DenoisedFrames spatial = runFrames(fx, room.scene, room.cpu, lights, exactMode(), 1, {1}, true, spatialOnly);
  const double eSpatial = relativeRmse(spatial.denoised[0], spatial.raw[0], surface);
  INFO("spatial only: " << eSpatial);
  CHECK(eSpatial <= 0.02);
}

TEST_CASE("RGB denoising keeps the colour of a red and a blue light", "[many_lights][denoise]") {
  GpuFixture fx;
  RoomSetup room(160, 120);  // more pixels: the channel means of one noisy frame are closer to their expectation
  std::vector<rb::LightSource> lights;
  lights.push_back(pointLight({-3.0, 2.5, 0.5}, {1.0f, 0.0f, 0.0f}, 12.0f));
  lights.push_back(pointLight({3.0, 2.5, -0.5}, {0.0f, 0.0f, 1.0f}, 12.0f));
  const std::vector<uint8_t> surface = surfaceOf(room.cpu);
  std::vector<float> exact = runFrames(fx, room.scene, room.cpu, lights, exactMode(), 1, {1}, false).raw[0];
  // One ray for two lights: each pixel picks red or blue, so the raw image is noisy in colour.
  DenoisedFrames run = runFrames(fx, room.scene, room.cpu, lights, stochastic(1), 16, {1, 16});
  auto channelMean = [&](const std::vector<float>& rgba, int c) {
    double sum = 0.0;
    for (size_t i = 0; i < surface.size(); ++i)
      if (surface[i]) sum += rgba[4 * i + c];
    return sum;
  };
  const double red = channelMean(exact, 0), blue = channelMean(exact, 2);
  REQUIRE(red > 0.0);
  REQUIRE(blue > 0.0);
  CHECK(channelMean(exact, 1) == 0.0);
  const double raw = relativeRmse(run.raw[0], exact, surface);
  for (size_t k = 0; k < run.denoised.size(); ++k) {
    const std::vector<float>& d = run.denoised[k];
    const double r = channelMean(d, 0) / red, b = channelMean(d, 2) / blue;
    const double e = relativeRmse(d, exact, surface);
    std::printf("[many_lights][denoise] red+blue, 1 ray, frame %s: denoised/exact red %.4f, blue %.4f; relative "
                "RMSE raw %.4f, denoised %.4f\n",
                k == 0 ? "1" : "16", r, b, raw, e);
    INFO("frame " << (k == 0 ? 1 : 16) << ": red ratio " << r << ", blue ratio " << b << ", RMSE raw " << raw
                  << " denoised " << e);
    // Edge-stopping weights depend on the values they filter, so the filter is not exactly energy-conserving on
    // binary colour noise: measured 0.7-1.4% (helper's sampler: 8 uniform candidates) and 1.5-3.8% (every light of
    // the tile weighed) after 16 frames. A lost or invented light would be off by far more.
    CHECK(std::fabs(r - 1.0) <= 0.05);
    CHECK(std::fabs(b - 1.0) <= 0.05);
    // And against the frame's own raw means: filtering moves colour around but hardly makes or loses any (the
    // first frame's rare bright samples lose a little; with a history the denoised image holds earlier frames,
    // whose means differ from the last raw frame's, so the bound is the one against exact).
    const double rawTolerance = k == 0 ? 0.04 : 0.05;
    INFO("denoised/raw red " << channelMean(d, 0) / channelMean(run.raw[k], 0) << ", blue "
                             << channelMean(d, 2) / channelMean(run.raw[k], 2));
    CHECK(std::fabs(channelMean(d, 0) / channelMean(run.raw[k], 0) - 1.0) <= rawTolerance);
    CHECK(std::fabs(channelMean(d, 2) / channelMean(run.raw[k], 2) - 1.0) <= rawTolerance);
    CHECK(channelMean(d, 1) <= 1e-3 * (red + blue));  // no green made up
    CHECK(e < raw);
  }
}

TEST_CASE("the effects front end denoises stochastic local lights, not exact ones",
          "[many_lights][denoise][hybrid_effects]") {
  GpuFixture fx;
  RoomSetup room(96, 72);
  const std::vector<rb::LightSource> lights = manyRoomLights();
  const std::vector<uint8_t> surface = surfaceOf(room.cpu);
  std::vector<float> exact = runFrames(fx, room.scene, room.cpu, lights, exactMode(), 1, {1}, false).raw[0];
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), room.scene);
  {
    GpuGBuffer gbuffer(fx, room.cpu);
    const uint32_t w = room.cpu.view.width, h = room.cpu.view.height;
    rb::HybridEffectsDesc desc;
    desc.effects = rb::kEffectLocalLights;
    desc.localLights.raysPerPixel = 4;
    auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
    RB_REQUIRE_OK(effects);
    rb::HybridEffects& fxs = *effects.value();
    auto frame = [&] {
      fx.runFrame([&](VkCommandBuffer cmd) {
        rb::HybridFrame f;
        f.gbuffer = gbuffer.desc();
        f.instances = built.instances;
        f.localLights = lights;
        RB_REQUIRE_OK(fxs.record(cmd, f));
      });
    };
    for (int i = 0; i < 4; ++i) frame();
    REQUIRE(fxs.localLightDenoiser() != nullptr);
    CHECK(fxs.localLightDenoiser()->signal() == rb::DenoiseSignal::Rgb);
    const rb::HybridOutputs& out = fxs.outputs();
    REQUIRE(out.localLights.image != VK_NULL_HANDLE);
    REQUIRE(out.localLightsRaw.image != VK_NULL_HANDLE);
    CHECK(out.localLights.image != out.localLightsRaw.image);
    CHECK(out.localLights.image == fxs.localLightDenoiser()->outputs().denoised);
    CHECK(out.localLights.format == VK_FORMAT_R16G16B16A16_SFLOAT);
    CHECK(out.localLightsRaw.image == fxs.localLightPass()->outputs().irradiance);
    const double eRaw = relativeRmse(readRgba16f(fx, out.localLightsRaw.image, w, h), exact, surface);
    const double eDenoised = relativeRmse(readRgba16f(fx, out.localLights.image, w, h), exact, surface);
    std::printf("[many_lights][denoise] HybridEffects, 4 rays, 4 frames: relative RMSE raw %.4f, localLights %.4f\n",
                eRaw, eDenoised);
    INFO("relative RMSE raw " << eRaw << ", denoised " << eDenoised);
    CHECK(eDenoised < 0.5 * eRaw);
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    (void)fx.device().waitIdle();
    const rb::HybridStats stats = fxs.stats();
    CHECK(stats.localLightsDenoise.gpuMs > 0.0);
    CHECK(stats.localLightsDenoise.rays == 0);
    CHECK(stats.totalGpuMs() >= stats.localLights.gpuMs + stats.localLightsDenoise.gpuMs);
    const uint64_t imagesWithDenoiser = fxs.memoryStats().of(rb::MemoryCategory::PassImages);

    // resetHistory: the next frame starts over, so it is noisier than a frame that kept its history.
    frame();
    const double eKept = relativeRmse(readRgba16f(fx, fxs.outputs().localLights.image, w, h), exact, surface);
    fxs.resetHistory();
    frame();
    const double eReset = relativeRmse(readRgba16f(fx, fxs.outputs().localLights.image, w, h), exact, surface);
    INFO("after 5 frames " << eKept << ", first frame after resetHistory " << eReset);
    CHECK(eReset > eKept);

    // disableDenoiser: the raw image, no denoiser.
    desc.localLights.disableDenoiser = true;
    RB_REQUIRE_OK(fxs.setDesc(desc));
    frame();
    CHECK(fxs.localLightDenoiser() == nullptr);
    CHECK(fxs.outputs().localLights.image == fxs.outputs().localLightsRaw.image);
    CHECK(readRgba16f(fx, fxs.outputs().localLights.image, w, h) ==
          readRgba16f(fx, fxs.outputs().localLightsRaw.image, w, h));
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    (void)fx.device().waitIdle();
    CHECK(fxs.stats().localLightsDenoise.gpuMs == 0.0);
    // The denoiser's own images (denoiser.h: 32 bytes per pixel) went with it, and the shared scratch with the last
    // denoiser (16 more).
    CHECK(imagesWithDenoiser - fxs.memoryStats().of(rb::MemoryCategory::PassImages) >= 48ull * w * h);

    // Exact mode has no noise: never denoised.
    desc.localLights.disableDenoiser = false;
    desc.localLights.mode = rb::ManyLightMode::Exact;
    RB_REQUIRE_OK(fxs.setDesc(desc));
    frame();
    CHECK(fxs.localLightDenoiser() == nullptr);
    CHECK(fxs.outputs().localLights.image == fxs.outputs().localLightsRaw.image);
    CHECK(readRgba16f(fx, fxs.outputs().localLights.image, w, h) == exact);

    // The effect off: no pass, no denoiser.
    desc.effects = 0;
    RB_REQUIRE_OK(fxs.setDesc(desc));
    CHECK(fxs.localLightPass() == nullptr);
    CHECK(fxs.localLightDenoiser() == nullptr);
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    (void)fx.device().waitIdle();
  }
  destroyScene(fx, built);
}

TEST_CASE("a denoiser description with an unknown signal fails naming the field", "[denoise][bad_input]") {
  GpuFixture fx;
  rb::DenoiserDesc desc;
  desc.signal = static_cast<rb::DenoiseSignal>(7);
  auto d = rb::Denoiser::create(fx.ctx(), desc);
  REQUIRE_FALSE(d);
  CHECK(d.error().code == rb::ErrorCode::InvalidArgument);
  CHECK(d.error().message.find("DenoiserDesc::signal") != std::string::npos);
  auto scalar = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(scalar);
  CHECK(scalar.value()->signal() == rb::DenoiseSignal::Scalar);
}

TEST_CASE("RGB temporal accumulation reprojects through camera motion", "[many_lights][denoise][temporal]") {
  GpuFixture fx;
  TestScene scene = makeRoom();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  // Eight frames while the camera slides sideways; the reference is the exact mode at the last view.
  std::vector<CpuGBuffer> views;
  for (int i = 0; i < 8; ++i) {
    SyntheticView v = roomView(128, 96);
    v.eye.x += 0.06 * i;
    v.target.x += 0.06 * i;
    views.push_back(traceGBuffer(embree, v));
  }
  const CpuGBuffer& last = views.back();
  const std::vector<rb::LightSource> lights = manyRoomLights();
  const std::vector<uint8_t> surface = surfaceOf(last);
  std::vector<float> exact = runFrames(fx, scene, last, lights, exactMode(), 1, {1}, false).raw[0];
  DenoisedFrames moving = runViews(fx, scene, views, lights, stochastic(4), {8});
  DenoisedFrames still = runFrames(fx, scene, last, lights, stochastic(4), 1, {1});
  const double eMoving = relativeRmse(moving.denoised[0], exact, surface);
  const double eOne = relativeRmse(still.denoised[0], exact, surface);
  std::printf("[many_lights][denoise] camera sliding over 8 frames: relative RMSE %.4f (one frame: %.4f)\n", eMoving,
              eOne);
  INFO("after 8 reprojected frames " << eMoving << ", after 1 frame " << eOne);
  // The history survives the motion: eight frames do nearly as well as eight still ones (0.06-0.08 here; 0.59-0.63 of
  // one frame's error with the two samplers measured). Without the history it would be about one frame's.
  CHECK(eMoving < 0.75 * eOne);
}


TEST_CASE("RGB denoising keeps a light's hot spot where it is", "[many_lights][denoise]") {
  GpuFixture fx;
  RoomSetup room;
  // The room's 32 lights and a bright one 5 cm above the box's top: a few very bright, noisy pixels (the
  // candidates often miss that light) among quiet ones.
  std::vector<rb::LightSource> lights = manyRoomLights();
  lights.push_back(pointLight({2.5, 1.25, 1.5}, {1.0f, 1.0f, 1.0f}, 2.0f, 2.0f));
  const std::vector<uint8_t> surface = surfaceOf(room.cpu);
  std::vector<float> exact = runFrames(fx, room.scene, room.cpu, lights, exactMode(), 1, {1}, false).raw[0];
  DenoisedFrames run = runFrames(fx, room.scene, room.cpu, lights, stochastic(4), 16, {16});
  const std::vector<float>& d = run.denoised[0];
  float hottest = 0.0f;
  for (size_t i = 0; i < surface.size(); ++i)
    if (surface[i]) hottest = std::max(hottest, exact[4 * i + 1]);
  // Pixels away from the hot spot that came out far brighter than they are: the hot spot spread into them.
  uint32_t spread = 0, quiet = 0;
  for (size_t i = 0; i < surface.size(); ++i) {
    if (!surface[i] || exact[4 * i + 1] > 0.05f * hottest) continue;
    ++quiet;
    spread += d[4 * i + 1] > 1.5f * exact[4 * i + 1] + 0.003f * hottest;
  }
  std::printf("[many_lights][denoise] hot spot %.1f: %u of %u quiet pixels brightened by it\n", hottest, spread, quiet);
  INFO("hottest " << hottest << ", quiet pixels " << quiet << ", brightened " << spread);
  CHECK(hottest > 50.0f);
  CHECK(spread <= 2);  // a tolerance from the mean of the two pixels' noise brightened 13 here
}
