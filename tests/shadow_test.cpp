// The shadow pass against ground truth: Embree's hard shadows, grazing light without acne, far from the
// origin, and the penumbra of a disk light.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>

#include <cmath>
#include <cstring>

#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

struct ShadowRun {
  std::vector<float> visibility;
  std::vector<float> hitDistance;
  rb::PassStats stats;
};

// Builds the scene (translated by `offset`), records the shadow pass on the synthetic G-buffer and reads the
// visibility back.
ShadowRun runShadowPass(GpuFixture& fx, const TestScene& scene, const CpuGBuffer& cpu, const rb::Light& light,
                        uint32_t raysPerPixel = 0, bool withDistance = false) {
  rb::ShadowPassDesc passDesc;
  passDesc.outputHitDistance = withDistance;
  auto pass = rb::ShadowPass::create(fx.ctx(), passDesc);
  RB_REQUIRE_OK(pass);
  rb::ShadowSettings settings;
  settings.raysPerPixel = raysPerPixel;
  ShadowRun run;
  runPassFrame(
      fx, scene, cpu, false,
      [&](VkCommandBuffer cmd, const rb::GBufferDesc& desc, const rb::TlasInfo& tlas) {
        RB_REQUIRE_OK(pass.value()->record(cmd, {.gbuffer = desc, .tlas = tlas, .light = light, .settings = settings}));
      },
      [&](const rb::GBufferDesc& desc) {
        run.visibility = readR16f(fx, pass.value()->outputs().visibility, desc.width, desc.height);
        if (withDistance) {
          REQUIRE(pass.value()->outputs().hitDistance != VK_NULL_HANDLE);
          run.hitDistance = readR32f(fx, pass.value()->outputs().hitDistance, desc.width, desc.height);
        } else {
          CHECK(pass.value()->outputs().hitDistance == VK_NULL_HANDLE);  // not asked for: not allocated
        }
      });
  run.stats = pass.value()->stats();
  return run;
}

rb::Light sun(glm::dvec3 towards, float radiusDegrees = 0.0f) {
  rb::Light l;
  glm::dvec3 d = glm::normalize(towards);
  l.direction[0] = float(d.x);
  l.direction[1] = float(d.y);
  l.direction[2] = float(d.z);
  l.angularRadiusDegrees = radiusDegrees;
  return l;
}

// Reference visibility at the exact hit point: the shading normal faces the light and nothing blocks it.
// `occluderDistance`, when given, receives the distance to the nearest occluder (0 where lit).
std::vector<int> referenceHardShadow(const EmbreeScene& embree, const CpuGBuffer& g, glm::dvec3 toLight,
                                     std::vector<float>* occluderDistance = nullptr) {
  std::vector<int> vis(g.hit.size(), -1);  // -1 = sky
  if (occluderDistance) occluderDistance->assign(g.hit.size(), 0.0f);
  toLight = glm::normalize(toLight);
  for (size_t i = 0; i < g.hit.size(); ++i) {
    if (!g.hit[i]) continue;
    glm::dvec3 n(g.normal[i]);
    if (glm::dot(n, toLight) <= 0.0) {
      vis[i] = 0;
      continue;
    }
    glm::dvec3 o = g.position[i] + n * 1e-4;
    float of[3] = {float(o.x), float(o.y), float(o.z)}, d[3] = {float(toLight.x), float(toLight.y), float(toLight.z)};
    ReferenceHit h = embree.intersect(of, d, 0.0f, 1e30f);
    vis[i] = h.hit ? 0 : 1;
    if (occluderDistance && h.hit) (*occluderDistance)[i] = h.t;
  }
  return vis;
}

}  // namespace

TEST_CASE("hard shadows match Embree away from shadow edges", "[shadow][embree]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const SyntheticView view = conformanceView(192, 128, 50.0);
  CpuGBuffer cpu = traceGBuffer(embree, view);
  glm::dvec3 toSun(0.4, 0.8, 0.3);
  ShadowRun run = runShadowPass(fx, scene, cpu, sun(toSun));
  ShadowRun withDistance = runShadowPass(fx, scene, cpu, sun(toSun), 0, /*withDistance=*/true);
  std::vector<float> refDistance;
  std::vector<int> ref = referenceHardShadow(embree, cpu, toSun, &refDistance);

  const int W = int(view.width), H = int(view.height);
  uint32_t compared = 0, agree = 0, shadowed = 0, lit = 0, sky = 0, skyLit = 0;
  uint32_t sameWithDistance = 0, occluded = 0, distanceAgree = 0;
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      size_t i = size_t(y) * W + x;
      if (ref[i] < 0) {
        ++sky;
        skyLit += run.visibility[i] == 1.0f;
        continue;
      }
      bool edge = false;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          int nx = std::clamp(x + dx, 0, W - 1), ny = std::clamp(y + dy, 0, H - 1);
          size_t j = size_t(ny) * W + nx;
          edge |= ref[j] != ref[i] || cpu.instance[j] != cpu.instance[i];
        }
      }
      if (edge) continue;
      ++compared;
      bool gpuLit = run.visibility[i] > 0.5f;
      agree += gpuLit == (ref[i] == 1);
      // The variant with the distance output finds the same visibility, and the nearest occluder.
      sameWithDistance += withDistance.visibility[i] == run.visibility[i];
      if (ref[i] == 0 && refDistance[i] > 0.0f && !gpuLit) {
        ++occluded;
        distanceAgree += std::fabs(withDistance.hitDistance[i] - refDistance[i]) <= 0.01f * refDistance[i] + 1e-3f;
      }
      shadowed += ref[i] == 0;
      lit += ref[i] == 1;
    }
  }
  INFO("compared " << compared << ", shadowed " << shadowed << ", lit " << lit << ", agree " << agree);
  REQUIRE(compared > uint32_t(W * H / 2));
  REQUIRE(shadowed > 500);  // the scene really casts shadows in view
  REQUIRE(lit > 500);
  CHECK(double(agree) / compared >= 0.999);
  CHECK(double(sameWithDistance) / compared >= 0.999);
  REQUIRE(occluded > 100);
  CHECK(double(distanceAgree) / occluded >= 0.99);
  CHECK(skyLit == sky);
  // Rays are counted: one per lit-facing surface pixel, none for sky or back-facing pixels.
  uint64_t facing = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    facing += cpu.hit[i] && glm::dot(glm::dvec3(cpu.normal[i]), glm::normalize(toSun)) > 0.0;
  }
  CHECK(run.stats.rays > 0);
  CHECK(double(run.stats.rays) >= 0.99 * double(facing));
  CHECK(double(run.stats.rays) <= 1.01 * double(facing));
}

TEST_CASE("grazing light shows no self-shadowing and a 1 cm gap still casts a shadow", "[shadow][robustness]") {
  GpuFixture fx;
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(60.0f, 4));
  const float mn[3] = {-0.5f, 0.01f, -0.5f}, mx[3] = {0.5f, 0.03f, 0.5f};  // a plate 1 cm above the plane
  scene.meshes.push_back(rbsamples::makeBox(mn, mx));
  scene.instances.push_back({0, translation(0, 0, 0)});
  scene.instances.push_back({1, translation(0, 0, 0)});
  EmbreeScene embree;
  addToEmbree(embree, scene);

  for (double elevation : {1.0, 5.0, 30.0}) {
    DYNAMIC_SECTION("sun elevation " << elevation << " degrees") {
      double e = glm::radians(elevation);
      glm::dvec3 toSun(std::cos(e), std::sin(e), 0.0);  // the sun in +X: the plate's shadow falls towards -X
      SyntheticView view;
      // Low on the side away from the sun, looking through the 1 cm gap: sees the open plane lit at a grazing
      // angle and, under the plate, the plane it shadows.
      view.eye = {-1.6, 0.06, 0.0};
      view.target = {-0.35, 0.0, 0.0};
      view.fovYDegrees = 12.0;
      view.width = 160;
      view.height = 120;
      CpuGBuffer cpu = traceGBuffer(embree, view);
      ShadowRun run = runShadowPass(fx, scene, cpu, sun(toSun));
      std::vector<int> ref = referenceHardShadow(embree, cpu, toSun);
      uint32_t planeLit = 0, planeLitAgree = 0, planeShadow = 0, planeShadowAgree = 0;
      for (int y = 1; y + 1 < int(view.height); ++y) {
        for (int x = 1; x + 1 < int(view.width); ++x) {
          size_t i = size_t(y) * view.width + x;
          if (cpu.instance[i] != 0) continue;  // plane pixels only
          bool edge = false;
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              size_t j = size_t(y + dy) * view.width + (x + dx);
              edge |= ref[j] != ref[i] || cpu.instance[j] != 0;
            }
          }
          if (edge) continue;
          if (ref[i] == 1) {
            ++planeLit;
            planeLitAgree += run.visibility[i] == 1.0f;
          } else {
            ++planeShadow;
            planeShadowAgree += run.visibility[i] == 0.0f;
          }
        }
      }
      INFO("lit " << planeLit << " (" << planeLitAgree << " lit on GPU), shadowed " << planeShadow << " ("
                  << planeShadowAgree << ")");
      REQUIRE(planeLit > 300);
      REQUIRE(planeShadow > 30);
      CHECK(planeLitAgree == planeLit);                       // no acne anywhere on the open plane
      CHECK(double(planeShadowAgree) / planeShadow >= 0.99);  // the 1 cm gap does not leak light
    }
  }
}

TEST_CASE("a scene 10 km from the origin shadows like the same scene at the origin", "[shadow][precision]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  const SyntheticView view = conformanceView(160, 120);
  CpuGBuffer cpu = traceGBuffer(embree, view);
  glm::dvec3 toSun(0.3, 0.5, 0.2);  // low sun: long shadows, grazing on the bumps
  ShadowRun atOrigin = runShadowPass(fx, scene, cpu, sun(toSun));

  // The same scene and camera 10 km away. The G-buffer is camera-relative, so it is the same images.
  TestScene far = scene;
  const double offset[3] = {10000.0, 0.0, -10000.0};
  for (SceneInstance& inst : far.instances) {
    inst.transform[3] += float(offset[0]);
    inst.transform[11] += float(offset[2]);
  }
  CpuGBuffer farCpu = cpu;
  farCpu.view.eye += glm::dvec3(offset[0], offset[1], offset[2]);
  ShadowRun farAway = runShadowPass(fx, far, farCpu, sun(toSun));
  uint32_t same = 0, surface = 0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    if (!cpu.hit[i]) continue;
    ++surface;
    same += std::fabs(atOrigin.visibility[i] - farAway.visibility[i]) < 1e-3f;
  }
  INFO("identical on " << same << " of " << surface << " surface pixels");
  CHECK(double(same) / surface >= 0.999);
}

TEST_CASE("soft shadow penumbra matches the analytic visible fraction of a disk light", "[shadow][soft]") {
  GpuFixture fx;
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(40.0f, 2));
  scene.meshes.push_back(rbsamples::makeSphere(1.0f, 192, 96));
  const glm::dvec3 centre(0.0, 3.0, 0.0);
  scene.instances.push_back({0, translation(0, 0, 0)});
  scene.instances.push_back({1, translation(0, 3.0f, 0)});
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.0, 1.2, 0.01};
  view.target = {0.0, 0.0, 0.0};
  view.up = {0.0, 0.0, -1.0};
  view.fovYDegrees = 90.0;
  view.width = 96;
  view.height = 96;
  CpuGBuffer cpu = traceGBuffer(embree, view);
  const float radiusDegrees = 8.0f;
  const uint32_t rays = 64;
  ShadowRun run = runShadowPass(fx, scene, cpu, sun({0.0, 1.0, 0.0}, radiusDegrees), rays);

  // The light as the pass defines it: directions normalize(L + tan(r) * d), d uniform on the unit disk in the
  // plane perpendicular to L. Integrated on a fine polar grid against the exact sphere.
  const double tanR = std::tan(glm::radians(double(radiusDegrees)));
  auto visibleFraction = [&](glm::dvec3 p) {
    const int rings = 96, sectors = 192;
    double visible = 0.0, total = 0.0;
    for (int a = 0; a < rings; ++a) {
      double r = std::sqrt((a + 0.5) / rings);
      for (int b = 0; b < sectors; ++b) {
        double phi = 2.0 * M_PI * (b + 0.5) / sectors;
        glm::dvec3 d = glm::normalize(glm::dvec3(tanR * r * std::cos(phi), 1.0, tanR * r * std::sin(phi)));
        glm::dvec3 oc = p - centre;
        double bq = glm::dot(oc, d), c = glm::dot(oc, oc) - 1.0;
        bool blocked = bq * bq - c > 0.0 && -bq - std::sqrt(bq * bq - c) > 0.0;
        visible += blocked ? 0.0 : 1.0;
        total += 1.0;
      }
    }
    return visible / total;
  };
  uint32_t penumbra = 0, within = 0;
  double sumError = 0.0;
  for (size_t i = 0; i < cpu.hit.size(); ++i) {
    if (!cpu.hit[i] || cpu.instance[i] != 0) continue;
    double f = visibleFraction(cpu.position[i]);
    if (f < 0.02 || f > 0.98) continue;
    ++penumbra;
    double sigma = std::sqrt(f * (1.0 - f) / rays);
    double err = double(run.visibility[i]) - f;
    sumError += err;
    within += std::fabs(err) <= 3.0 * sigma + 1.0 / rays;
  }
  INFO("penumbra pixels " << penumbra << ", within 3 sigma " << within << ", mean error " << sumError / penumbra);
  REQUIRE(penumbra > 200);
  CHECK(double(within) / penumbra >= 0.99);
  CHECK(std::fabs(sumError / penumbra) < 0.01);  // unbiased on average
}

TEST_CASE("single-sided geometry seen from behind still casts shadows (rays hit both sides)",
          "[shadow][double-sided]") {
  GpuFixture fx;
  TestScene scene;
  scene.meshes.push_back(rbsamples::makeGrid(20.0f, 4));
  // A 3 m single-sided roof 1 m above the ground, its only side facing up to the sun: the shadow rays from the
  // ground reach its back face, which a renderer culling back faces would let the light through.
  scene.meshes.push_back(rbsamples::makeGrid(3.0f, 2));
  scene.instances.push_back({0, translation(0, 0, 0)});
  scene.instances.push_back({1, translation(0, 1, 0)});
  EmbreeScene embree;
  addToEmbree(embree, scene);
  SyntheticView view;
  view.eye = {0.0, 6.0, 6.0};
  view.target = {0.0, 0.0, 0.0};
  view.width = 128;
  view.height = 96;
  CpuGBuffer cpu = traceGBuffer(embree, view);
  const glm::dvec3 toSun(0.2, 1.0, 0.1);
  ShadowRun run = runShadowPass(fx, scene, cpu, sun(toSun));
  std::vector<int> ref = referenceHardShadow(embree, cpu, toSun);
  uint32_t groundShadowed = 0, agree = 0, compared = 0;
  for (size_t i = 0; i < ref.size(); ++i) {
    if (!cpu.hit[i] || cpu.instance[i] != 0) continue;  // ground pixels
    ++compared;
    groundShadowed += ref[i] == 0;
    agree += (run.visibility[i] >= 0.5f) == (ref[i] == 1);
  }
  INFO("ground pixels " << compared << ", shadowed by the roof " << groundShadowed << ", agree " << agree);
  REQUIRE(groundShadowed > 200);
  CHECK(double(agree) / compared >= 0.995);
}
