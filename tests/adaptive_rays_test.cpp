// Adaptive rays per pixel (raybridge/ray_schedule.h): the budget controller on a simulated cost, and on lavapipe
// the ray budget as counted by the shaders, the plan's agreement with the counters, and where the rays go.
#include <raybridge/raybridge.h>

#include <catch2/catch_test_macros.hpp>
#include <catch2/generators/catch_generators.hpp>
#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "adaptive_budget.h"
#include "embree_reference.h"
#include "synthetic_gbuffer.h"
#include "test_scene.h"
#include "test_support.h"

using namespace rbtest;

namespace {

// The plan image (R16G16F) as (rays, mean) pairs.
std::vector<float> readPlan(GpuFixture& fx, VkImage image, uint32_t w, uint32_t h) {
  std::vector<uint8_t> raw = readPassImage(fx, image, w, h, 4);
  std::vector<float> out(size_t(w) * h * 2);
  for (size_t i = 0; i < out.size(); ++i) {
    uint16_t half;
    std::memcpy(&half, raw.data() + 2 * i, 2);
    out[i] = glm::unpackHalf1x16(half);
  }
  return out;
}

// A plan's tiles (of tw x th pixels, aligned to multiples of themselves): the surface pixels of a tile share one
// count, sky pixels have none. `mixed` counts the tiles where they do not; `surfaceTiles` those with a surface pixel.
struct TileCheck {
  uint32_t mixed = 0, skyWithRays = 0, surfaceTiles = 0;
};
TileCheck checkTiles(const std::vector<float>& plan, const CpuGBuffer& cpu, uint32_t w, uint32_t h, uint32_t tw,
                     uint32_t th) {
  TileCheck c;
  for (uint32_t ty = 0; ty < h; ty += th) {
    for (uint32_t tx = 0; tx < w; tx += tw) {
      float count = -1.0f;
      bool mixed = false;
      for (uint32_t y = ty; y < std::min(ty + th, h); ++y) {
        for (uint32_t x = tx; x < std::min(tx + tw, w); ++x) {
          const size_t p = size_t(y) * w + x;
          if (!cpu.hit[p]) {
            c.skyWithRays += plan[2 * p] != 0.0f;
          } else if (count < 0.0f) {
            count = plan[2 * p];
          } else {
            mixed = mixed || plan[2 * p] != count;
          }
        }
      }
      c.surfaceTiles += count >= 0.0f;
      c.mixed += mixed;
    }
  }
  return c;
}

// The planned rays summed over the image.
uint64_t plannedRays(const std::vector<float>& plan) {
  uint64_t sum = 0;
  for (size_t i = 0; i < plan.size(); i += 2) sum += uint64_t(plan[i]);
  return sum;
}

const char* granularityName(rb::AdaptiveRayGranularity g) {
  return g == rb::AdaptiveRayGranularity::Tile ? "tile" : "pixel";
}

struct AdaptiveScene {
  GpuFixture& fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  CpuGBuffer cpu;
  std::unique_ptr<rb::AccelerationStructureService> service;
  BuiltScene built;
  std::unique_ptr<GpuGBuffer> gbuffer;
  uint32_t surfacePixels = 0;
  AdaptiveScene(GpuFixture& f, uint32_t w, uint32_t h) : fx(f) {
    addToEmbree(embree, scene);
    cpu = traceGBuffer(embree, conformanceView(w, h));
    for (uint8_t hit : cpu.hit) surfacePixels += hit;
    auto s = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(s);
    service = std::move(s.value());
    built = buildScene(fx, *service, scene);
    gbuffer = std::make_unique<GpuGBuffer>(fx, cpu);
  }
  ~AdaptiveScene() {
    gbuffer.reset();
    destroyScene(fx, built);
  }
  rb::HybridFrame frame() const {
    rb::HybridFrame f;
    f.gbuffer = gbuffer->desc();
    f.tlas = &built.tlas;
    f.light.direction[0] = 0.4f;
    f.light.direction[1] = 1.0f;
    f.light.direction[2] = 0.3f;
    f.light.angularRadiusDegrees = 4.0f;  // soft: the shadows are a mean of rays
    return f;
  }
};

}  // namespace

TEST_CASE("the ray budget controller settles on its time target despite a fixed cost and frames in flight",
          "[adaptive]") {
  // Simulated pass: 0.3 ms of fixed cost plus 2e-7 ms per ray; measurements come back two frames late.
  auto cost = [](double rays) { return 0.3 + 2e-7 * rays; };
  const double target = 1.5;  // ms: the fixed point is (1.5 - 0.3) / 2e-7 = 6e6 rays
  rb::RayBudgetController c;
  std::vector<uint64_t> planned;
  rb::PassStats latest;
  for (uint64_t frame = 1; frame <= 40; ++frame) {
    if (frame > 2) {
      latest.frame = frame - 2;
      latest.rays = planned[frame - 3];
      latest.gpuMs = cost(double(latest.rays));
    }
    planned.push_back(c.next(frame, latest, target, 2e7, 1e3, 1e9));
  }
  INFO("final budget " << planned.back());
  CHECK(std::abs(double(planned.back()) - 6e6) < 0.03 * 6e6);
  CHECK(std::abs(cost(double(planned.back())) - target) < 0.03 * target);
  // One measurement is taken in once: asking again without a new frame keeps the budget.
  const uint64_t again = c.next(41, latest, target, 2e7, 1e3, 1e9);
  CHECK(again == planned.back());
  // One wild measurement (a near-zero reading, a wrapped tick count) moves the budget by at most kMaxBudgetStep,
  // and the controller walks back to the target.
  for (double wild : {1e-6, 1.8e13}) {
    INFO("wild gpuMs " << wild);
    rb::RayBudgetController w = c;
    rb::PassStats odd = latest;
    odd.frame = 39;
    odd.gpuMs = wild;
    const uint64_t afterWild = w.next(42, odd, target, 2e7, 1e3, 1e9);
    CHECK(double(afterWild) <= rb::kMaxBudgetStep * 1.001 * double(again));
    CHECK(double(afterWild) >= double(again) / (rb::kMaxBudgetStep * 1.001));
    std::vector<uint64_t> plan(43, afterWild);
    for (uint64_t frame = 43; frame <= 60; ++frame) {
      rb::PassStats m;
      m.frame = frame - 2;
      m.rays = plan[frame - 2];
      m.gpuMs = cost(double(m.rays));
      plan.push_back(w.next(frame, m, target, 2e7, 1e3, 1e9));
    }
    CHECK(std::abs(double(plan.back()) - 6e6) < 0.03 * 6e6);
  }
  // Only a quarter of the plan traced (half resolution): the controller scales the planned budget, not the rays
  // counted, so it still settles where the pass takes the target time (traced = budget / 4).
  rb::RayBudgetController quarter;
  std::vector<uint64_t> budgets;
  rb::PassStats q;
  for (uint64_t frame = 1; frame <= 40; ++frame) {
    if (frame > 2) {
      q.frame = frame - 2;
      q.rays = budgets[frame - 3] / 4;
      q.gpuMs = cost(double(q.rays));
    }
    budgets.push_back(quarter.next(frame, q, target, 2e7, 1e3, 1e9));
  }
  INFO("quarter-traced budget " << budgets.back());
  CHECK(std::abs(cost(double(budgets.back()) / 4.0) - target) < 0.03 * target);
  // The bounds hold whatever the measurement says.
  rb::RayBudgetController fast;
  rb::PassStats cheap;
  cheap.frame = 1;
  cheap.rays = 1000;
  cheap.gpuMs = 1e-6;
  CHECK(fast.next(1, cheap, target, 5e5, 1e3, 1e6) <= uint64_t(1e6));
  rb::RayBudgetController slow;
  rb::PassStats dear = cheap;
  dear.gpuMs = 1e6;
  uint64_t low = 0;
  for (int i = 0; i < 40; ++i) {
    dear.frame = uint64_t(i + 1);
    low = slow.next(uint64_t(i + 2), dear, target, 5e5, 1e3, 1e6);
  }
  CHECK(low == 1000);
}

TEST_CASE("a per-tile cap under one tile's rays still traces one tile a frame", "[adaptive][ao]") {
  GpuFixture fx;
  const uint32_t w = 64, h = 48;
  AdaptiveScene s(fx, w, h);
  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectAo;
  desc.ao.raysPerPixel = 4;
  desc.ao.range = 2.0f;
  desc.ao.schedule.adaptive.enabled = true;
  desc.ao.schedule.adaptive.granularity = rb::AdaptiveRayGranularity::Tile;
  desc.ao.schedule.adaptive.maxRaysPerFrame = 16;  // a quarter of the default 8x8 tile
  auto fxr = rb::HybridEffects::create(fx.ctx(), s.service.get(), desc);
  RB_REQUIRE_OK(fxr);
  rb::HybridEffects& effects = *fxr.value();
  const rb::HybridFrame frame = s.frame();
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });  // uniform: no history
  const uint64_t tileRays = uint64_t(rb::kDefaultAdaptiveTileWidth) * rb::kDefaultAdaptiveTileHeight;
  // Each tile rounds its share (budget / surface pixels, here 1/32 of a ray) up to one ray a pixel with that
  // probability, so a frame may trace nothing; over frames some tile must, and never more than one tile's rays.
  uint64_t total = 0;
  for (int i = 0; i < 8; ++i) {
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
    const uint64_t rays = effects.stats().ao.rays;
    INFO("frame " << i << ": " << rays << " rays");
    CHECK(rays <= tileRays);
    total += rays;
  }
  CHECK(total > 0);
}

TEST_CASE("adaptive AO at 8K (7680x4320) without history shares its budget evenly: the weight sum does not overflow",
          "[adaptive][ao][large]") {
  // Every pixel without history weighs the most a pixel can (0.52), and 33 million of them summed in the fixed
  // point of RbPlanCounters::weightSum once exceeded 32 bits at 8K: the wrapped sum made every share 36 times too
  // large, the first tiles took the whole budget at maxRaysPerPixel and three quarters of the image got no ray.
  GpuFixture fx;
  const uint32_t w = 7680, h = 4320;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  // Straight down onto the 40 x 40 ground from 3 units: every pixel is a surface.
  SyntheticView view;
  view.eye = {0.0, 3.0, 5.0};
  view.target = {0.0, 0.0, 5.0};
  view.up = {0.0, 0.0, -1.0};
  view.width = w;
  view.height = h;
  const CpuGBuffer cpu = traceGBuffer(embree, view);
  uint64_t surface = 0;
  for (uint8_t hit : cpu.hit) surface += hit;
  REQUIRE(surface == uint64_t(w) * h);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  {
    GpuGBuffer gbuffer(fx, cpu);
    rb::HybridEffectsDesc desc;
    desc.effects = rb::kEffectAo;
    desc.ao.raysPerPixel = 2;  // the budget: one ray everywhere (the minimum) and one more shared by weight
    desc.ao.range = 0.25f;
    desc.ao.schedule.adaptive.enabled = true;
    auto fxr = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
    RB_REQUIRE_OK(fxr);
    rb::HybridEffects& effects = *fxr.value();
    rb::HybridFrame frame;
    frame.gbuffer = gbuffer.desc();
    frame.tlas = &built.tlas;
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });  // uniform: no history
    effects.resetHistory();  // the history exists but is void: every pixel counts as without history
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
    const rb::AoOutputs& o = effects.aoPass()->outputs();
    REQUIRE(o.rayPlan != VK_NULL_HANDLE);
    const std::vector<float> plan = readPlan(fx, o.rayPlan, w, h);
    uint64_t none = 0, near = 0;  // pixels planned no ray; pixels planned 1 to 3 rays (2 on average)
    for (size_t p = 0; p < size_t(w) * h; ++p) {
      none += plan[2 * p] == 0.0f;
      near += plan[2 * p] >= 1.0f && plan[2 * p] <= 3.0f;
    }
    const uint64_t rays = effects.stats().ao.rays;
    INFO(rays << " rays traced for a budget of " << 2 * surface << "; " << none << " pixels planned none, " << near
              << " planned 1 to 3 of " << surface);
    CHECK(rays <= 2 * surface);
    CHECK(rays >= 2 * surface * 9 / 10);
    CHECK(none <= surface / 100);
    CHECK(near >= surface * 99 / 100);
  }
  destroyScene(fx, built);
}

TEST_CASE("adaptive AO traces no more rays than its budget, the plan matches the counters, and rays go where the "
          "history is uncertain (per pixel and per tile)",
          "[adaptive][ao]") {
  const rb::AdaptiveRayGranularity granularity = GENERATE(rb::AdaptiveRayGranularity::Pixel,
                                                          rb::AdaptiveRayGranularity::Tile);
  INFO("granularity " << granularityName(granularity));
  const bool tiles = granularity == rb::AdaptiveRayGranularity::Tile;
  GpuFixture fx;
  const uint32_t w = 64, h = 48;
  AdaptiveScene s(fx, w, h);
  REQUIRE(s.surfacePixels > 1000);
  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectAo;
  desc.ao.raysPerPixel = 4;
  desc.ao.range = 2.0f;
  desc.ao.schedule.adaptive.enabled = true;
  desc.ao.schedule.adaptive.granularity = granularity;
  desc.ao.schedule.adaptive.maxRaysPerFrame = 3 * uint64_t(s.surfacePixels);  // under the uniform 4 per pixel
  auto fxr = rb::HybridEffects::create(fx.ctx(), s.service.get(), desc);
  RB_REQUIRE_OK(fxr);
  rb::HybridEffects& effects = *fxr.value();
  const rb::HybridFrame frame = s.frame();

  // Frame 1 has no history: uniform rays, no plan.
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
  CHECK(effects.aoPass()->outputs().rayPlan == VK_NULL_HANDLE);
  CHECK(effects.stats().ao.rays == 4ull * s.surfacePixels);

  for (int i = 0; i < 6; ++i) {
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
    const rb::AoOutputs& o = effects.aoPass()->outputs();
    REQUIRE(o.rayPlan != VK_NULL_HANDLE);
    const uint64_t rays = effects.stats().ao.rays;
    const std::vector<float> plan = readPlan(fx, o.rayPlan, w, h);
    uint64_t planned = 0;
    uint32_t maxRays = 0;
    for (size_t p = 0; p < size_t(w) * h; ++p) {
      planned += uint64_t(plan[2 * p]);
      maxRays = std::max(maxRays, uint32_t(plan[2 * p]));
      if (!s.cpu.hit[p]) CHECK(plan[2 * p] == 0.0f);  // sky: no ray
    }
    INFO("frame " << i << ": " << rays << " rays counted, " << planned << " planned, budget "
                  << desc.ao.schedule.adaptive.maxRaysPerFrame);
    CHECK(rays == planned);  // the shader traced exactly what the plan says
    CHECK(rays <= desc.ao.schedule.adaptive.maxRaysPerFrame);
    CHECK(rays >= desc.ao.schedule.adaptive.maxRaysPerFrame * 9 / 10);  // and the budget is spent
    CHECK(maxRays <= rb::kDefaultAdaptiveMaxRaysFactor * 4);
    if (tiles) {
      // The default tile: one count per 8x8 block of surface pixels.
      const TileCheck t = checkTiles(plan, s.cpu, w, h, rb::kDefaultAdaptiveTileWidth, rb::kDefaultAdaptiveTileHeight);
      CHECK(t.mixed == 0);
      CHECK(t.skyWithRays == 0);
    }
    if (i == 5 && !tiles) {
      // Where the history is settled at fully open (1) or closed (0) the estimate is certain; where it is in
      // between (corners, contact) it is not: those pixels get more rays.
      double certainRays = 0, uncertainRays = 0;
      uint32_t certain = 0, uncertain = 0;
      for (size_t p = 0; p < size_t(w) * h; ++p) {
        if (!s.cpu.hit[p]) continue;
        const float mean = plan[2 * p + 1];
        if (mean > 0.99f || mean < 0.01f) {
          certainRays += plan[2 * p];
          ++certain;
        } else if (mean > 0.25f && mean < 0.75f) {
          uncertainRays += plan[2 * p];
          ++uncertain;
        }
      }
      REQUIRE(certain > 50);
      REQUIRE(uncertain > 20);
      INFO("mean rays: certain pixels " << certainRays / certain << ", uncertain " << uncertainRays / uncertain);
      CHECK(uncertainRays / uncertain > 2.0 * (certainRays / certain));
    }
    if (i == 5 && tiles) {
      // Per tile: the tiles whose pixels' histories are the most uncertain on average (binomial variance of the
      // reprojected mean) get more rays per pixel than the most certain ones.
      std::vector<std::pair<double, double>> byTile;  // (mean variance, rays per surface pixel)
      const uint32_t tw = rb::kDefaultAdaptiveTileWidth, th = rb::kDefaultAdaptiveTileHeight;
      for (uint32_t ty = 0; ty < h; ty += th) {
        for (uint32_t tx = 0; tx < w; tx += tw) {
          double variance = 0.0, rays = 0.0;
          uint32_t n = 0;
          for (uint32_t y = ty; y < std::min(ty + th, h); ++y) {
            for (uint32_t x = tx; x < std::min(tx + tw, w); ++x) {
              const size_t p = size_t(y) * w + x;
              if (!s.cpu.hit[p]) continue;
              const double mean = plan[2 * p + 1];
              variance += mean * (1.0 - mean);
              rays += plan[2 * p];
              ++n;
            }
          }
          if (n >= tw * th / 2) byTile.push_back({variance / n, rays / n});
        }
      }
      REQUIRE(byTile.size() >= 16);
      std::sort(byTile.begin(), byTile.end());
      const size_t quarter = byTile.size() / 4;
      double certainRays = 0, uncertainRays = 0;
      for (size_t k = 0; k < quarter; ++k) {
        certainRays += byTile[k].second;
        uncertainRays += byTile[byTile.size() - 1 - k].second;
      }
      INFO(byTile.size() << " tiles; mean rays per pixel: most certain quarter " << certainRays / quarter
                         << ", most uncertain quarter " << uncertainRays / quarter << "; variance "
                         << byTile.front().first << " .. " << byTile.back().first);
      CHECK(uncertainRays > 1.5 * certainRays);
    }
  }
}

TEST_CASE("adaptive rays per tile: every surface pixel of a tile gets the same rays within the budget, at full and "
          "half resolution, with any tile shape and over the shadow classifier's tiles",
          "[adaptive][tiles]") {
  GpuFixture fx;
  const uint32_t w = 64, h = 48;
  AdaptiveScene s(fx, w, h);
  REQUIRE(s.surfacePixels > 1000);
  const rb::HybridFrame frame = s.frame();
  // Runs `frames` frames after the uniform first and checks each plan's tiles of tw x th pixels and its budget.
  auto run = [&](rb::HybridEffects& effects, bool ao, uint32_t tw, uint32_t th, uint64_t budget, bool exactCounts) {
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
    for (int i = 0; i < 4; ++i) {
      fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
      const VkImage image = ao ? effects.aoPass()->outputs().rayPlan : effects.shadowPass()->outputs().rayPlan;
      REQUIRE(image != VK_NULL_HANDLE);
      const std::vector<float> plan = readPlan(fx, image, w, h);
      const TileCheck t = checkTiles(plan, s.cpu, w, h, tw, th);
      const uint64_t rays = ao ? effects.stats().ao.rays : effects.stats().shadow.rays;
      const uint64_t planned = plannedRays(plan);
      INFO("frame " << i << ": " << t.surfaceTiles << " tiles of " << tw << "x" << th << " pixels, " << t.mixed
                    << " mixed; " << rays << " rays counted, " << planned << " planned, budget " << budget);
      REQUIRE(t.surfaceTiles > 4);
      CHECK(t.mixed == 0);
      CHECK(t.skyWithRays == 0);
      CHECK(planned <= budget);
      CHECK(rays <= budget);
      if (exactCounts) CHECK(rays == planned);
    }
  };
  rb::HybridEffectsDesc desc;
  SECTION("AO at full resolution, 8x4 tiles, a budget under the minimum of one ray everywhere") {
    desc.effects = rb::kEffectAo;
    desc.ao.raysPerPixel = 4;
    desc.ao.schedule.adaptive.enabled = true;
    desc.ao.schedule.adaptive.tileWidth = 8;
    desc.ao.schedule.adaptive.tileHeight = 4;
    // Half a ray per surface pixel: half the tiles get one ray per pixel, the claim cuts the rest to whole tiles.
    desc.ao.schedule.adaptive.maxRaysPerFrame = s.surfacePixels / 2;
    auto e = rb::HybridEffects::create(fx.ctx(), s.service.get(), desc);
    RB_REQUIRE_OK(e);
    run(*e.value(), true, 8, 4, desc.ao.schedule.adaptive.maxRaysPerFrame, true);
  }
  SECTION("AO at half resolution: the default 8x8 tiles of launch cells are 16x16 pixels") {
    desc.effects = rb::kEffectAo;
    desc.ao.raysPerPixel = 4;
    desc.ao.schedule.halfResolution = true;
    desc.ao.schedule.adaptive.enabled = true;
    desc.ao.schedule.adaptive.maxRaysPerFrame = 3ull * s.surfacePixels;
    auto e = rb::HybridEffects::create(fx.ctx(), s.service.get(), desc);
    RB_REQUIRE_OK(e);
    // A quarter of the plan is traced: the counters are not the plan.
    run(*e.value(), true, 16, 16, desc.ao.schedule.adaptive.maxRaysPerFrame, false);
  }
  SECTION("soft shadows over the tile classifier's launch, 4x8 tiles") {
    desc.effects = rb::kEffectShadows;
    desc.shadows.raysPerPixel = 4;
    desc.shadows.schedule.tileClassifier = true;
    desc.shadows.schedule.adaptive.enabled = true;
    desc.shadows.schedule.adaptive.tileWidth = 4;
    desc.shadows.schedule.adaptive.tileHeight = 8;
    auto e = rb::HybridEffects::create(fx.ctx(), s.service.get(), desc);
    RB_REQUIRE_OK(e);
    // Pixels facing away from the light are planned rays but trace none.
    run(*e.value(), false, 4, 8, 4ull * s.surfacePixels, false);
  }
}

TEST_CASE("adaptive soft shadows stay within the uniform rays by default and follow a time target down (per pixel "
          "and per tile)",
          "[adaptive][shadows]") {
  const rb::AdaptiveRayGranularity granularity = GENERATE(rb::AdaptiveRayGranularity::Pixel,
                                                          rb::AdaptiveRayGranularity::Tile);
  INFO("granularity " << granularityName(granularity));
  const bool tiles = granularity == rb::AdaptiveRayGranularity::Tile;
  GpuFixture fx;
  const uint32_t w = 48, h = 36;
  AdaptiveScene s(fx, w, h);
  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectShadows;
  desc.shadows.raysPerPixel = 4;
  desc.shadows.schedule.adaptive.enabled = true;  // no cap, no time target: the uniform rays, redistributed
  desc.shadows.schedule.adaptive.granularity = granularity;
  auto fxr = rb::HybridEffects::create(fx.ctx(), s.service.get(), desc);
  RB_REQUIRE_OK(fxr);
  rb::HybridEffects& effects = *fxr.value();
  const rb::HybridFrame frame = s.frame();
  uint64_t untargeted = 0;  // the last frame's rays without a time target
  for (int i = 0; i < 4; ++i) {
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
    const rb::ShadowOutputs& o = effects.shadowPass()->outputs();
    const uint64_t rays = effects.stats().shadow.rays;
    untargeted = rays;
    INFO("frame " << i << ": " << rays << " rays, " << s.surfacePixels << " surface pixels");
    CHECK(rays <= 4ull * s.surfacePixels);
    if (i > 0) {
      REQUIRE(o.rayPlan != VK_NULL_HANDLE);
      const std::vector<float> plan = readPlan(fx, o.rayPlan, w, h);
      uint64_t planned = 0;
      for (size_t p = 0; p < size_t(w) * h; ++p) planned += uint64_t(plan[2 * p]);
      // Pixels facing away from the light are planned rays but trace none.
      CHECK(rays <= planned);
    }
  }
  // A time target no pass can meet: the budget falls to its floor (one ray per 64 pixels; per tile, at least one
  // ray in every pixel of a tile) within a few frames.
  desc.shadows.schedule.adaptive.timeBudgetMs = 1e-6f;
  RB_REQUIRE_OK(effects.setDesc(desc));
  uint64_t last = 0;
  for (int i = 0; i < 12; ++i) {
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
    last = effects.stats().shadow.rays;
  }
  // (Per tile the first targeted frame can already be at the floor: the budget is rounded to whole tiles.)
  INFO("rays: without the target " << untargeted << ", after 12 targeted frames " << last);
  const uint64_t floor = tiles ? std::max<uint64_t>(uint64_t(w) * h / 64 + 1,
                                                    rb::kDefaultAdaptiveTileWidth * rb::kDefaultAdaptiveTileHeight)
                               : uint64_t(w) * h / 64 + 1;
  CHECK(last <= floor);
  CHECK(last < untargeted / 4);
}

TEST_CASE("bad adaptive ray settings are named", "[adaptive][bad_input]") {
  GpuFixture fx;
  AdaptiveScene s(fx, 16, 12);
  auto ao = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(ao);
  auto expectError = [&](const rb::AoSettings& settings, const char* needle) {
    fx.runFrame([&](VkCommandBuffer cmd) {
      rb::Status st = ao.value()->record(cmd,
                                         {.gbuffer = s.gbuffer->desc(), .tlas = s.built.tlas, .settings = settings});
      REQUIRE_FALSE(st.ok());
      INFO(st.error().message);
      CHECK(st.error().code == rb::ErrorCode::InvalidArgument);
      CHECK(st.error().message.find(needle) != std::string::npos);
    });
  };
  rb::AoSettings a;
  a.schedule.adaptive.enabled = true;
  expectError(a, "history is nullptr");
  auto rgb = rb::Denoiser::create(fx.ctx(), rb::DenoiserDesc{rb::DenoiseSignal::Rgb});
  RB_REQUIRE_OK(rgb);
  a.schedule.history = rgb.value().get();
  expectError(a, "DenoiseSignal::Scalar");
  auto scalar = rb::Denoiser::create(fx.ctx());
  RB_REQUIRE_OK(scalar);
  a.schedule.history = scalar.value().get();
  a.schedule.adaptive.timeBudgetMs = std::nanf("");
  expectError(a, "timeBudgetMs");
  a.schedule.adaptive.timeBudgetMs = 0.0f;
  a.schedule.adaptive.maxRaysPerPixel = 1000;
  expectError(a, "maxRaysPerPixel 1000 exceeds 256");
  a.schedule.adaptive.maxRaysPerPixel = 2;
  a.schedule.adaptive.minRaysPerPixel = 3;
  expectError(a, "minRaysPerPixel 3 exceeds maxRaysPerPixel 2");
  a.schedule.adaptive.minRaysPerPixel = 0;
  a.schedule.adaptive.tileWidth = 3;
  expectError(a, "tileWidth 3 must be 0 (default 8x8) or a power of two at most 8");
  a.schedule.adaptive.tileWidth = 0;
  a.schedule.adaptive.tileHeight = 16;
  expectError(a, "tileHeight 16 must be 0");
  a.schedule.adaptive.tileHeight = 0;
  a.schedule.adaptive.granularity = static_cast<rb::AdaptiveRayGranularity>(7);
  expectError(a, "granularity has an unknown value (7)");
  a.schedule.adaptive.granularity = rb::AdaptiveRayGranularity::Tile;

  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectAo;
  desc.ao.schedule.adaptive.enabled = true;
  desc.ao.disableDenoiser = true;
  auto bad = rb::HybridEffects::create(fx.ctx(), s.service.get(), desc);
  REQUIRE_FALSE(bad.ok());
  CHECK(bad.error().message.find("ao.schedule.adaptive") != std::string::npos);

  auto shadow = rb::ShadowPass::create(fx.ctx(), rb::ShadowPassDesc{true});
  RB_REQUIRE_OK(shadow);
  fx.runFrame([&](VkCommandBuffer cmd) {
    rb::ShadowSettings ss;
    ss.schedule.adaptive.enabled = true;
    ss.schedule.history = scalar.value().get();
    rb::Light soft;
    soft.angularRadiusDegrees = 2.0f;
    rb::Status st = shadow.value()->record(
        cmd, {.gbuffer = s.gbuffer->desc(), .tlas = s.built.tlas, .light = soft, .settings = ss});
    REQUIRE_FALSE(st.ok());
    CHECK(st.error().message.find("outputHitDistance") != std::string::npos);
  });
}
