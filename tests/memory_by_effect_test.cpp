// HybridEffects::memoryByEffect (issue 30): each effect's pass images follow the per-pixel formula of
// docs/integration.md ("Memory by effect") at two resolutions, the effects' sum is the Context's pass memory, and an
// effect switched off gives its bytes back.
#include <catch2/catch_test_macros.hpp>

#include <cstdio>

#include "effects_rig.h"

using namespace rbtest;

namespace {

// docs/integration.md, "Memory by effect": bytes of pass images per pixel of the G-buffer, `high` with local lights.
// Shadows: visibility R16F (2) + the scalar denoiser's own images (history 2 x RG16F, view distance 2 x R16F,
// temporal RG16F, output R16F: 18). AO: the same, plus its half-resolution samples R16F at a quarter of the pixels.
// Reflections and local lights: radiance RGBA16F (8) + the RGB denoiser's own (history 2 x RGBA16F, surface 2 x RG16F,
// output RGBA16F: 32). Shared: one R8 change mask per denoised effect, and the denoisers' one DenoiserScratch (scalar
// a-trous ping RG16F, RGB a-trous ping RGBA16F, RGB guide RG32UI: 20).
constexpr uint64_t kShadowBytesPerPixel = 20;
constexpr uint64_t kAoBytesPerPixel = 20;
constexpr uint64_t kAoHalfResolutionBytesPerSample = 2;
constexpr uint64_t kRgbEffectBytesPerPixel = 40;
constexpr uint64_t kChangeMaskBytesPerPixel = 1;
constexpr uint64_t kDenoiserScratchBytesPerPixel = 20;

struct Measured {
  rb::EffectMemoryStats byEffect;
  rb::MemoryStats context;
};

// `high` with local lights at width x height: three frames, then the memory.
Measured measure(GpuFixture& fx, uint32_t width, uint32_t height) {
  EffectsRig rig(fx, width, height);
  rb::HybridEffectsDesc desc = rb::withPreset({}, rb::Preset::High);
  desc.effects |= rb::kEffectLocalLights;
  auto created = rb::HybridEffects::create(fx.ctx(), &rig.service(), desc);
  RB_REQUIRE_OK(created);
  rb::HybridEffects& effects = *created.value();
  const std::vector<rb::LightSource> lights = lampRow(2);
  auto frame = [&] { rig.record(effects, lights); };
  for (int i = 0; i < 3; ++i) frame();
  Measured m{effects.memoryByEffect(), fx.ctx().memoryStats()};
  CHECK(m.byEffect.total().of(rb::MemoryCategory::PassImages) ==
        effects.memoryStats().of(rb::MemoryCategory::PassImages));

  // AO off: its bytes go back once the frames in flight are done; the other effects keep theirs.
  desc.effects &= ~rb::kEffectAo;
  RB_REQUIRE_OK(effects.setDesc(desc));
  frame();
  (void)fx.device().waitIdle();
  fx.ctx().releaseAfterIdle();
  const rb::EffectMemoryStats after = effects.memoryByEffect();
  CHECK(after.ao.total() == 0);
  CHECK(after.ao.allocations == 0);
  CHECK(after.shadows.of(rb::MemoryCategory::PassImages) == m.byEffect.shadows.of(rb::MemoryCategory::PassImages));
  CHECK(after.reflections.total() == m.byEffect.reflections.total());
  // The AO change mask went with the AO denoiser; the 1x1 neutral images outputs() names for an effect that is off
  // came (neutral_images.h: a few hundred bytes).
  const uint64_t sharedLeft = m.byEffect.shared.of(rb::MemoryCategory::PassImages) -
                              kChangeMaskBytesPerPixel * width * height;
  CHECK(after.shared.of(rb::MemoryCategory::PassImages) >= sharedLeft);
  CHECK(after.shared.of(rb::MemoryCategory::PassImages) <= sharedLeft + 4096);
  return m;
}

}  // namespace

TEST_CASE("memory by effect follows the documented formula at two resolutions", "[memory][hybrid_effects]") {
  GpuFixture fx;
  for (const auto& [w, h] : {std::pair<uint32_t, uint32_t>{64, 48}, std::pair<uint32_t, uint32_t>{128, 80}}) {
    INFO(w << "x" << h);
    const Measured m = measure(fx, w, h);
    const uint64_t pixels = uint64_t(w) * h;
    const rb::EffectMemoryStats& e = m.byEffect;
    auto images = [](const rb::MemoryStats& s) { return uint64_t(s.of(rb::MemoryCategory::PassImages)); };
    std::printf("[memory] %ux%u pass images, bytes per pixel: shadows %.2f, AO %.2f, reflections %.2f, local lights "
                "%.2f, shared %.2f; all %.2f\n",
                w, h, double(images(e.shadows)) / pixels, double(images(e.ao)) / pixels,
                double(images(e.reflections)) / pixels, double(images(e.localLights)) / pixels,
                double(images(e.shared)) / pixels, double(images(e.total())) / pixels);
    CHECK(images(e.shadows) == kShadowBytesPerPixel * pixels);
    CHECK(images(e.ao) == kAoBytesPerPixel * pixels + kAoHalfResolutionBytesPerSample * (w / 2) * (h / 2));
    CHECK(images(e.reflections) == kRgbEffectBytesPerPixel * pixels);
    CHECK(images(e.localLights) == kRgbEffectBytesPerPixel * pixels);
    CHECK(images(e.shared) == (4 * kChangeMaskBytesPerPixel + kDenoiserScratchBytesPerPixel) * pixels);
    // The sum is the Context's pass memory: nothing of HybridEffects is left unattributed.
    for (rb::MemoryCategory c :
         {rb::MemoryCategory::ShaderTables, rb::MemoryCategory::PassImages, rb::MemoryCategory::PassBuffers})
      CHECK(e.total().of(c) == m.context.of(c));
    // Every effect holds shader tables and buffers of its own; the acceleration structures are nobody's.
    for (const rb::MemoryStats* s : {&e.shadows, &e.ao, &e.reflections, &e.localLights}) {
      CHECK(s->of(rb::MemoryCategory::ShaderTables) > 0);
      CHECK(s->of(rb::MemoryCategory::BlasStorage) == 0);
      CHECK(s->of(rb::MemoryCategory::Tlas) == 0);
    }
  }
}
