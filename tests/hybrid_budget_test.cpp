// HybridEffectsDesc::budgetMs on lavapipe, with validation: bad budgets are named errors; under its floor every effect
// runs at its cheapest and the floor is reported; with room the levels climb back to the description. The division
// itself is tests/frame_budget_test.cpp's (injected timings).
#include <catch2/catch_test_macros.hpp>

#include <cmath>
#include <limits>

#include "effects_rig.h"

using namespace rbtest;

namespace {

struct BudgetRun {
  rb::HybridStats stats;
  rb::HybridStats firstStats;  // after the third frame
};

// `high` with four glossy reflection rays, four local-light rays and eight lamps at 64x48 for `frames` frames under
// `budgetMs` (0 = none).
BudgetRun run(GpuFixture& fx, float budgetMs, int frames) {
  EffectsRig rig(fx, 64, 48);
  rb::HybridEffectsDesc desc = rb::withPreset({}, rb::Preset::High);
  desc.effects |= rb::kEffectLocalLights;
  desc.localLights.raysPerPixel = 4;
  desc.reflections.raysPerPixel = 4;
  desc.budgetMs = budgetMs;
  auto created = rb::HybridEffects::create(fx.ctx(), &rig.service(), desc);
  RB_REQUIRE_OK(created);
  // Eight lamps: more than the rays, so the four rays are stochastic (with fewer lights than rays every light gets
  // its own ray, whatever the count).
  const std::vector<rb::LightSource> lights = lampRow(8);
  BudgetRun out;
  for (int i = 0; i < frames; ++i) {
    rig.record(*created.value(), lights);
    if (i == 2) out.firstStats = created.value()->stats();
  }
  out.stats = created.value()->stats();
  return out;
}

}  // namespace

TEST_CASE("HybridEffectsDesc::budgetMs: a value that is no budget is a named error", "[budget][hybrid]") {
  GpuFixture fx;
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), -1.0f, std::numeric_limits<float>::infinity(), 1001.0f}) {
    rb::HybridEffectsDesc desc = rb::withPreset({}, rb::Preset::High);
    desc.budgetMs = bad;
    auto created = rb::HybridEffects::create(fx.ctx(), nullptr, desc);
    REQUIRE_FALSE(created);
    INFO(created.error().message);
    CHECK(created.error().code == rb::ErrorCode::InvalidArgument);
    CHECK(created.error().message.find("budgetMs") != std::string::npos);
    CHECK(created.error().message.find("0 for none") != std::string::npos);
  }
  // And setDesc refuses it without changing the description.
  auto created = rb::HybridEffects::create(fx.ctx(), nullptr, rb::withPreset({}, rb::Preset::High));
  RB_REQUIRE_OK(created);
  rb::HybridEffectsDesc desc = created.value()->desc();
  desc.budgetMs = -3.0f;
  CHECK_FALSE(created.value()->setDesc(desc));
  CHECK(created.value()->desc().budgetMs == 0.0f);
}

TEST_CASE("a frame budget under the floor runs every effect at its cheapest and reports the floor",
          "[budget][hybrid]") {
  GpuFixture fx;
  if (!fx.ctx().deviceInfo().timestampsSupported) SKIP("the device has no timestamps: a frame budget needs them");
  const BudgetRun none = run(fx, 0.0f, 12);
  const BudgetRun tight = run(fx, 0.001f, 12);
  const rb::FrameBudgetStats& b = tight.stats.budget;
  CHECK(none.stats.budget.budgetMs == 0.0f);
  CHECK(none.stats.hook.gpuMs > 0.0);  // the hook is timed with or without a budget
  CHECK(b.budgetMs == 0.001f);
  CHECK(b.measurements >= 5);
  CHECK(b.belowFloor);
  CHECK(b.floorMs > b.fixedMs);
  CHECK(b.fixedMs > 0.0);
  CHECK(b.reflectionLevel == 3);  // one ray (4 / 2 / 1), then half resolution
  CHECK(b.localLightLevel == 2);  // 4 rays / 4
  // The adaptive effects trace far fewer rays than the description's uniform ones; reflections at half resolution a
  // quarter; local lights one ray where they traced four.
  CHECK(tight.stats.shadow.rays * 4 < none.stats.shadow.rays);
  CHECK(tight.stats.ao.rays * 2 < none.stats.ao.rays);
  CHECK(tight.stats.reflection.rays * 3 < none.stats.reflection.rays);
  CHECK(tight.stats.localLights.rays * 3 < none.stats.localLights.rays);
}

TEST_CASE("a frame budget with room climbs back to the description's levels", "[budget][hybrid]") {
  GpuFixture fx;
  if (!fx.ctx().deviceInfo().timestampsSupported) SKIP("the device has no timestamps: a frame budget needs them");
  const BudgetRun none = run(fx, 0.0f, 12);
  const BudgetRun roomy = run(fx, 1000.0f, 48);
  // Every effect starts at its cheapest (the first frames hold any budget)...
  CHECK(roomy.firstStats.budget.reflectionLevel == 3);
  CHECK(roomy.firstStats.budget.localLightLevel == 2);
  // ...and five steps later (reflections 3 -> 0, local lights 2 -> 0), one per kBudgetSettleFrames, runs as described.
  const rb::FrameBudgetStats& b = roomy.stats.budget;
  CHECK(b.reflectionLevel == 0);
  CHECK(b.localLightLevel == 0);
  CHECK(b.levelSteps == 5);
  CHECK_FALSE(b.belowFloor);
  // The adaptive effects share what is left, far more than the uniform rays take: they trace more than those (up to
  // AdaptiveRaySettings::maxRaysPerPixel, 4x the uniform ones, where the denoiser's history asks).
  CHECK(roomy.stats.shadow.rays > none.stats.shadow.rays);
  CHECK(roomy.stats.ao.rays > none.stats.ao.rays);
  CHECK(b.shadowsMs > roomy.stats.shadow.gpuMs);
}

TEST_CASE("a record() that fails after the hook's start timestamp still times the frame", "[budget][hybrid]") {
  GpuFixture fx;
  if (!fx.ctx().deviceInfo().timestampsSupported) SKIP("the device has no timestamps to time record() with");
  EffectsRig rig(fx, 32, 24);
  auto created = rb::HybridEffects::create(fx.ctx(), &rig.service(), rb::withPreset({}, rb::Preset::SoftShadows));
  RB_REQUIRE_OK(created);
  rb::HybridEffects& effects = *created.value();
  rig.record(effects);
  rig.record(effects);
  // An instance without a mesh: the frame passes record()'s own checks, and the TLAS build inside it fails, after
  // the hook's start timestamp was written.
  const uint64_t failedFrame = fx.ctx().frameIndex();
  const rb::Instance noMesh;
  const rb::Status failed = rig.recordEdited(effects, [&](rb::HybridFrame& f) { f.instances = std::span(&noMesh, 1); });
  REQUIRE_FALSE(failed.ok());
  INFO(failed.error().message);
  CHECK(failed.error().message.find("recordTlasBuild") != std::string::npos);
  // The failed frame has its end timestamp too: it is measured (read back as the next frame starts), not left "not
  // ready" (gpuMs 0) for ever.
  rig.record(effects);
  CHECK(effects.stats().hook.frame == failedFrame);
  CHECK(effects.stats().hook.gpuMs > 0.0);
  // And the frames after it are timed as before.
  rig.record(effects);
  CHECK(effects.stats().hook.frame == failedFrame + 1);
  CHECK(effects.stats().hook.gpuMs > 0.0);
}
