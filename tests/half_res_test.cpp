// Half-resolution AO and reflections: one sample per 2x2 block, traced for the pixel the frame's rotation picks, and
// the depth-aware upsample to the full-resolution output, against the same passes at full resolution.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "raybridge_shader_interface.glsl"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

// The pixel sample `cell` traces for in `frame` (RB_HALF_RES_OFFSET_*, shaders/half_resolution.glsl).
glm::uvec2 tracedPixel(glm::uvec2 cell, uint64_t frame, uint32_t w, uint32_t h) {
  const uint32_t f = uint32_t(frame);
  return {std::min(2 * cell.x + RB_HALF_RES_OFFSET_X(f), w - 1), std::min(2 * cell.y + RB_HALF_RES_OFFSET_Y(f), h - 1)};
}

// Surface pixels among the pixels the half-resolution samples of `frame` trace for: the pass's rays per ray count.
uint64_t tracedSurfacePixels(const CpuGBuffer& cpu, uint64_t frame) {
  const uint32_t w = cpu.view.width, h = cpu.view.height;
  uint64_t n = 0;
  for (uint32_t j = 0; j < (h + 1) / 2; ++j) {
    for (uint32_t i = 0; i < (w + 1) / 2; ++i) {
      const glm::uvec2 p = tracedPixel({i, j}, frame, w, h);
      n += cpu.hit[size_t(p.y) * w + p.x];
    }
  }
  return n;
}

struct AoRun {
  std::vector<float> ao;
  rb::PassStats stats;
  uint64_t frame = 0;  // Context::frameIndex() of the recording: which pixels the samples traced
};

AoRun runAo(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu, const rb::AoSettings& settings) {
  auto pass = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  AoRun run;
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        run.frame = fx.ctx().frameIndex();
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) { run.ao = readR16f(fx, pass.value()->outputs().ao, desc.width, desc.height); });
  run.stats = pass.value()->stats();
  return run;
}

struct ReflectionRun {
  std::vector<glm::vec4> radiance;
  rb::PassStats stats;
  uint64_t frame = 0;
};

ReflectionRun runReflections(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu,
                             const std::vector<rb::Material>& materials, const rb::ReflectionSettings& settings) {
  auto pass = rb::ReflectionPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  RB_REQUIRE_OK(pass.value()->setMaterials(materials, {}));
  ReflectionRun run;
  runPassFrame(
      fx, scene, cpu, true,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        run.frame = fx.ctx().frameIndex();
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) {
        std::vector<float> v = readRgba16f(fx, pass.value()->outputs().radiance, desc.width, desc.height);
        run.radiance.resize(v.size() / 4);
        for (size_t i = 0; i < run.radiance.size(); ++i)
          run.radiance[i] = glm::vec4(v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3]);
      });
  run.stats = pass.value()->stats();
  return run;
}

// A plane of 40 x 40 m, seen with its horizon, so the image has sky too.
TestScene openPlane() {
  TestScene s;
  s.meshes.push_back(rbsamples::makeGrid(40.0f, 40));
  s.instances.push_back({0, translation(0, 0, 0)});
  return s;
}

SyntheticView planeView(uint32_t w, uint32_t h) {
  SyntheticView v;
  v.eye = {0.0, 1.5, 6.0};
  v.target = {0.0, 0.6, 0.0};
  v.fovYDegrees = 50.0;
  v.width = w;
  v.height = h;
  return v;
}

}  // namespace

TEST_CASE("half-resolution AO on an open plane equals full resolution, with a quarter of the rays", "[halfres][ao]") {
  const TestScene scene = openPlane();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const CpuGBuffer cpu = traceGBuffer(embree, planeView(48, 36));
  rb::AoSettings settings;
  settings.raysPerPixel = 8;
  settings.range = 1.0f;
  AoRun full, half;
  {
    GpuFixture fx;
    full = runAo(fx, scene, cpu, settings);
  }
  {
    GpuFixture fx;
    settings.schedule.halfResolution = true;
    half = runAo(fx, scene, cpu, settings);
  }
  uint64_t hits = 0, sky = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    hits += cpu.hit[i];
    sky += !cpu.hit[i];
    REQUIRE(full.ao[i] == 1.0f);  // nothing to occlude
    REQUIRE(half.ao[i] == full.ao[i]);
  }
  REQUIRE(hits > 1000);
  REQUIRE(sky > 100);
  CHECK(full.stats.rays == hits * 8);
  // Exactly the samples whose pixel is a surface trace, settings.raysPerPixel rays each: about a quarter.
  const uint64_t traced = tracedSurfacePixels(cpu, half.frame);
  INFO("full " << full.stats.rays << " rays, half " << half.stats.rays << ", " << traced << " traced surface pixels");
  CHECK(half.stats.rays == traced * 8);
  CHECK(std::fabs(double(half.stats.rays) / double(full.stats.rays) - 0.25) < 0.02);
}

TEST_CASE("half-resolution AO stays close to full resolution and keeps silhouettes that bilinear blurs",
          "[halfres][ao]") {
  // A box in front of a wall, on a floor: the box's open front and top against the occluded floor and wall behind.
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(20.0f, 20));
  const float boxMin[3] = {-0.7f, 0.0f, -0.5f}, boxMax[3] = {0.7f, 1.2f, 0.5f};
  scene.meshes.push_back(rbsamples::makeBox(boxMin, boxMax, 2));
  const float wallMin[3] = {-10.0f, 0.0f, -1.3f}, wallMax[3] = {10.0f, 5.0f, -1.0f};
  scene.meshes.push_back(rbsamples::makeBox(wallMin, wallMax, 8));
  scene.instances.push_back({0, translation(0, 0, 0)});
  scene.instances.push_back({1, translation(0, 0, 0)});
  scene.instances.push_back({2, translation(0, 0, 0)});
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.0, 2.6, 4.2};  // straight on: no box side seen edge-on (a feature thinner than the samples)
  view.target = {0.0, 0.6, -0.6};
  view.fovYDegrees = 45.0;
  view.width = 64;
  view.height = 48;
  const uint32_t w = view.width, h = view.height;
  const CpuGBuffer cpu = traceGBuffer(embree, view);
  rb::AoSettings settings;
  settings.raysPerPixel = 512;  // converged: what is left is the upsample's own error
  settings.range = 1.5f;
  AoRun full, half;
  {
    GpuFixture fx;
    full = runAo(fx, scene, cpu, settings);
  }
  {
    GpuFixture fx;
    settings.schedule.halfResolution = true;
    half = runAo(fx, scene, cpu, settings);
  }
  // Fresh contexts record in the same frame, so a sample traces its pixel with the full-resolution pass's noise:
  // the upsample must hand each traced pixel its sample unchanged.
  REQUIRE(full.frame == half.frame);
  std::vector<float> samples(size_t((w + 1) / 2) * ((h + 1) / 2));
  uint32_t tracedExact = 0, tracedSurface = 0;
  for (uint32_t j = 0; j < (h + 1) / 2; ++j) {
    for (uint32_t i = 0; i < (w + 1) / 2; ++i) {
      const glm::uvec2 p = tracedPixel({i, j}, half.frame, w, h);
      const size_t k = size_t(p.y) * w + p.x;
      samples[size_t(j) * ((w + 1) / 2) + i] = half.ao[k];  // sky: 1, as the pass writes it
      if (!cpu.hit[k]) continue;
      ++tracedSurface;
      tracedExact += half.ao[k] == full.ao[k];
    }
  }
  CHECK(tracedExact == tracedSurface);

  // A plain bilinear upsample of the same samples (their positions on this frame's grid), for comparison.
  auto axis = [](uint32_t x, uint32_t offset, uint32_t cells, uint32_t size, uint32_t& c0, uint32_t& c1, float& f) {
    const int below = int(std::floor((float(x) - float(offset)) * 0.5f));
    c0 = uint32_t(std::clamp(below, 0, int(cells) - 1));
    c1 = uint32_t(std::clamp(below + 1, 0, int(cells) - 1));
    const float x0 = float(std::min(2 * c0 + offset, size - 1)), x1 = float(std::min(2 * c1 + offset, size - 1));
    f = x1 > x0 ? std::clamp((float(x) - x0) / (x1 - x0), 0.0f, 1.0f) : 0.0f;
  };
  const uint32_t frame = uint32_t(half.frame);
  auto bilinear = [&](uint32_t x, uint32_t y) {
    uint32_t x0, x1, y0, y1;
    float fx, fy;
    axis(x, RB_HALF_RES_OFFSET_X(frame), (w + 1) / 2, w, x0, x1, fx);
    axis(y, RB_HALF_RES_OFFSET_Y(frame), (h + 1) / 2, h, y0, y1, fy);
    auto s = [&](uint32_t i, uint32_t j) { return samples[size_t(j) * ((w + 1) / 2) + i]; };
    return (1 - fx) * (1 - fy) * s(x0, y0) + fx * (1 - fy) * s(x1, y0) + (1 - fx) * fy * s(x0, y1) +
           fx * fy * s(x1, y1);
  };

  // Silhouettes: surface pixels within a pixel of a depth step (over 10% of the view distance) or of the sky.
  auto distance = [&](uint32_t x, uint32_t y) {
    const size_t k = size_t(y) * w + x;
    return cpu.hit[k] ? glm::length(cpu.position[k] - view.eye) : 1e9;
  };
  auto step = [&](uint32_t x, uint32_t y) {
    const double d = distance(x, y);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int qx = int(x) + dx, qy = int(y) + dy;
        if (qx < 0 || qy < 0 || qx >= int(w) || qy >= int(h)) continue;
        if (std::fabs(distance(uint32_t(qx), uint32_t(qy)) - d) > 0.1 * d) return true;
      }
    }
    return false;
  };
  double sumAll = 0.0, sumEdgeHalf = 0.0, sumEdgeBilinear = 0.0;
  uint32_t surface = 0, edges = 0;
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      const size_t k = size_t(y) * w + x;
      if (!cpu.hit[k]) {
        REQUIRE(half.ao[k] == 1.0f);  // sky: open, as at full resolution
        continue;
      }
      const double e = double(half.ao[k]) - full.ao[k];
      sumAll += e * e;
      ++surface;
      if (!step(x, y)) continue;
      const double b = double(bilinear(x, y)) - full.ao[k];
      sumEdgeHalf += e * e;
      sumEdgeBilinear += b * b;
      ++edges;
    }
  }
  const double rmse = std::sqrt(sumAll / surface), edgeHalf = std::sqrt(sumEdgeHalf / edges),
               edgeBilinear = std::sqrt(sumEdgeBilinear / edges);
  std::printf(
      "[halfres] AO 512 rays, 64x48: RMSE half vs full %.4f; at %u silhouette pixels %.4f (plain bilinear %.4f)\n",
      rmse, edges, edgeHalf, edgeBilinear);
  INFO("RMSE " << rmse << " over " << surface << " pixels; silhouettes (" << edges << "): depth-aware " << edgeHalf
               << ", bilinear " << edgeBilinear);
  REQUIRE(edges > 60);
  CHECK(edgeBilinear > 0.08);  // the scene has silhouettes a blur gets wrong
  CHECK(rmse < 0.04);
  CHECK(edgeHalf < 0.5 * edgeBilinear);
}

TEST_CASE("half-resolution AO at odd sizes writes every pixel in every frame of the rotation", "[halfres][ao]") {
  GpuFixture fx;
  const uint32_t w = 33, h = 17;
  // Two scenes of one size, alternating on one pass: inside a closed box every ray hits (AO 0 everywhere); on the
  // open plane nothing occludes (AO 1 everywhere). A pixel the plane's frame does not write keeps its 0.
  TestScene inside;
  const float roomMin[3] = {-3.0f, -3.0f, -3.0f}, roomMax[3] = {3.0f, 3.0f, 3.0f};
  inside.meshes.push_back(rbsamples::makeBox(roomMin, roomMax, 2));
  inside.instances.push_back({0, translation(0, 0, 0)});
  const TestScene plane = openPlane();
  struct Staged {
    CpuGBuffer cpu;
    std::unique_ptr<rb::AccelerationStructureService> service;
    BuiltScene built;
    std::unique_ptr<GpuGBuffer> gbuffer;
  };
  auto stage = [&](const TestScene& scene, const SyntheticView& view) {
    EmbreeScene embree;
    addToEmbree(embree, scene);
    Staged s;
    s.cpu = traceGBuffer(embree, view);
    auto service = rb::AccelerationStructureService::create(fx.ctx());
    RB_REQUIRE_OK(service);
    s.service = std::move(service.value());
    s.gbuffer = std::make_unique<GpuGBuffer>(fx, s.cpu);
    s.built = buildScene(fx, *s.service, scene, s.gbuffer->cameraRelativeTlas());
    return s;
  };
  SyntheticView roomView;
  roomView.eye = {0.3, 0.2, 0.5};
  roomView.target = {1.0, -0.4, -2.0};
  roomView.width = w;
  roomView.height = h;
  Staged room = stage(inside, roomView);
  Staged open = stage(plane, planeView(w, h));
  for (uint8_t hit : room.cpu.hit) REQUIRE(hit);

  auto pass = rb::AoPass::create(fx.ctx());
  RB_REQUIRE_OK(pass);
  rb::AoSettings settings;
  settings.raysPerPixel = 4;
  settings.range = 1e6f;
  settings.schedule.halfResolution = true;
  std::set<uint32_t> offsets;
  uint64_t lastFrame = 0;
  for (int round = 0; round < 4; ++round) {
    for (const Staged* s : {&room, &open}) {
      fx.runFrame([&](VkCommandBuffer cmd) {
        lastFrame = fx.ctx().frameIndex();
        RB_REQUIRE_OK(
            pass.value()->record(cmd, {.gbuffer = s->gbuffer->desc(), .tlas = s->built.tlas, .settings = settings}));
      });
      const std::vector<float> ao = readR16f(fx, pass.value()->outputs().ao, w, h);
      const float expected = s == &room ? 0.0f : 1.0f;
      uint32_t wrong = 0;
      for (float v : ao) wrong += v != expected;
      INFO((s == &room ? "closed room" : "open plane") << ", frame " << lastFrame);
      CHECK(wrong == 0);
    }
    offsets.insert(RB_HALF_RES_OFFSET_X(uint32_t(lastFrame)) + 2 * RB_HALF_RES_OFFSET_Y(uint32_t(lastFrame)));
    fx.ctx().beginFrame();  // three frames per round: the plane's frames go through all four offsets
  }
  CHECK(offsets.size() == 4);
  for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
  (void)fx.device().waitIdle();
  // The last frame's rays: the samples whose (clamped) pixel is a surface, 4 rays each.
  CHECK(pass.value()->stats().rays == tracedSurfacePixels(open.cpu, lastFrame) * 4);
  pass.value().reset();
  for (Staged* s : {&room, &open}) {
    s->gbuffer.reset();
    destroyScene(fx, s->built);
  }
}

TEST_CASE("half-resolution reflections of a mirror floor match full resolution and keep its coverage",
          "[halfres][reflection]") {
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(12.0f, 12));
  const float mn[3] = {-0.6f, 0.0f, -0.6f}, mx[3] = {0.6f, 1.5f, 0.6f};
  scene.meshes.push_back(rbsamples::makeBox(mn, mx, 2));
  scene.instances.push_back({0, translation(0, 0, 0), 0});
  scene.instances.push_back({1, translation(0, 0, -1.5f), 1});
  std::vector<rb::Material> materials(2);
  materials[1].baseColor[0] = 0.8f;
  materials[1].baseColor[1] = 0.05f;
  materials[1].baseColor[2] = 0.05f;
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.3, 1.2, 4.0};
  view.target = {0.0, 0.4, -1.0};
  view.width = 96;
  view.height = 72;
  const uint32_t w = view.width, h = view.height;
  const CpuGBuffer cpu = traceGBuffer(embree, view, {0.0f, 1.0f});  // floor a mirror, box rough
  rb::ReflectionSettings settings;
  settings.lighting.sunDirection[0] = 0.3f;
  settings.lighting.sunDirection[1] = 1.0f;
  settings.lighting.sunDirection[2] = 0.6f;
  ReflectionRun full, half;
  {
    GpuFixture fx;
    full = runReflections(fx, scene, cpu, materials, settings);
  }
  {
    GpuFixture fx;
    settings.schedule.halfResolution = true;
    half = runReflections(fx, scene, cpu, materials, settings);
  }
  uint32_t sky = 0, rough = 0, mirror = 0, coverageAgrees = 0, smooth = 0, close = 0;
  double sumAbs = 0.0;
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      const size_t k = size_t(y) * w + x;
      const glm::vec4 f = full.radiance[k], s = half.radiance[k];
      sky += !cpu.hit[k];
      rough += cpu.hit[k] && cpu.instance[k] == 1;
      coverageAgrees += (s.a == 0.0f) == (f.a == 0.0f) && (s.a == 0.0f || s.a == 1.0f);
      if (f.a == 0.0f) continue;
      ++mirror;
      const float e = glm::length(glm::vec3(s) - glm::vec3(f));
      sumAbs += e;
      // Where the full-resolution reflection is smooth around the pixel (no reflected edge within 2 pixels), the
      // upsample must reproduce it; at reflected edges it interpolates, as any upsample does.
      bool flat = x >= 2 && y >= 2 && x + 2 < w && y + 2 < h;
      for (int dy = -2; flat && dy <= 2; ++dy) {
        for (int dx = -2; flat && dx <= 2; ++dx) {
          const glm::vec4 q = full.radiance[size_t(int(y) + dy) * w + size_t(int(x) + dx)];
          flat = q.a != 0.0f && glm::length(glm::vec3(q) - glm::vec3(f)) < 0.05f;
        }
      }
      if (!flat) continue;
      ++smooth;
      close += e < 0.02f;
    }
  }
  const double meanError = sumAbs / mirror;
  INFO("sky " << sky << ", rough " << rough << ", mirror " << mirror << " (" << smooth << " smooth, " << close
              << " close), mean |error| " << meanError << "; rays full " << full.stats.rays << ", half "
              << half.stats.rays);
  REQUIRE(sky > 100);
  REQUIRE(rough > 100);
  REQUIRE(smooth > 1000);
  CHECK(coverageAgrees == w * h);  // a = 0 exactly where the full-resolution pass has a = 0: sky and rough
  CHECK(close == smooth);
  CHECK(meanError < 0.02);
  // One mirror ray per traced floor pixel (plus the shadow rays of hits): about a quarter of full resolution.
  const double ratio = double(half.stats.rays) / double(full.stats.rays);
  CHECK((ratio > 0.22 && ratio < 0.28));
}

TEST_CASE("toggling half resolution between frames of the front end re-makes and releases its images",
          "[halfres][hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const uint32_t w = 48, h = 36;
  std::vector<float> roughness(scene.instances.size(), 0.2f);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(w, h), roughness);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene);
  GpuGBuffer gbuffer(fx, cpu);

  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectAo | rb::kEffectReflections;  // both denoised (the default)
  auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
  RB_REQUIRE_OK(effects);
  rb::HybridEffects& fxs = *effects.value();
  auto passImages = [&] { return fx.ctx().memoryStats().of(rb::MemoryCategory::PassImages); };
  auto settle = [&] {
    for (uint32_t i = 0; i < fx.ctx().framesInFlight(); ++i) fx.ctx().beginFrame();
    (void)fx.device().waitIdle();
  };
  VkDeviceSize fullBytes = 0, halfBytes = 0;
  for (int i = 0; i < 6; ++i) {
    const bool halfRes = i % 2 == 1;
    desc.ao.schedule.halfResolution = desc.reflections.schedule.halfResolution = halfRes;
    RB_REQUIRE_OK(fxs.setDesc(desc));
    fx.runFrame([&](VkCommandBuffer cmd) {
      rb::HybridFrame f;
      f.gbuffer = gbuffer.desc();
      f.instances = built.instances;
      RB_REQUIRE_OK(fxs.record(cmd, f));
    });
    const rb::HybridOutputs& out = fxs.outputs();
    REQUIRE(out.ao.image != VK_NULL_HANDLE);
    REQUIRE(out.reflection.image != VK_NULL_HANDLE);
    const std::vector<float> ao = readR16f(fx, out.aoRaw.image, w, h);
    const std::vector<float> reflection = readRgba16f(fx, out.reflectionRaw.image, w, h);
    uint32_t bad = 0, covered = 0;
    for (float v : ao) bad += !(v >= 0.0f && v <= 1.0f);
    for (size_t k = 0; k < reflection.size(); ++k) bad += !std::isfinite(reflection[k]);
    for (size_t k = 0; k < cpu.hit.size(); ++k) covered += reflection[4 * k + 3] == 1.0f;
    INFO("frame " << i << (halfRes ? " (half resolution)" : " (full resolution)"));
    CHECK(bad == 0);
    CHECK(covered == uint32_t(std::count(cpu.hit.begin(), cpu.hit.end(), uint8_t(1))));  // every surface reflects
    settle();  // retired images are destroyed now
    (halfRes ? halfBytes : fullBytes) = passImages();
    if (i >= 2) CHECK(passImages() == (halfRes ? halfBytes : fullBytes));  // same images each time
  }
  // The samples: an R16F and an RGBA16F image of a quarter of the pixels, only while on.
  const VkDeviceSize samples = VkDeviceSize((w + 1) / 2) * ((h + 1) / 2) * (2 + 8);
  INFO("pass images: full resolution " << fullBytes << " bytes, half " << halfBytes);
  CHECK(halfBytes >= fullBytes + samples);
  CHECK(halfBytes <= fullBytes + 4 * samples);  // allocation granularity at most
  effects.value().reset();
  settle();
  destroyScene(fx, built);
}
