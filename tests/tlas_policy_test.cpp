// TlasBuildMode::Adaptive: the refit-quality measure (TlasMotionMeasure) and the policy that rebuilds on it or on
// the refit count; HybridEffectsDesc::tlasMode.
#include <catch2/catch_test_macros.hpp>

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "synthetic_gbuffer.h"
#include "test_scene.h"
#include "tlas_motion.h"

using namespace rbtest;

namespace {

// n origins on a jittered grid over [0, size)^2 at y = 0 (a city on a plane: one axis has no extent).
std::vector<float> planeOrigins(uint32_t side, float size, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.2f, 0.2f);
  std::vector<float> o;
  const float step = size / float(side);
  for (uint32_t z = 0; z < side; ++z) {
    for (uint32_t x = 0; x < side; ++x) {
      o.push_back((float(x) + 0.5f + jitter(rng)) * step);
      o.push_back(0.0f);
      o.push_back((float(z) + 0.5f + jitter(rng)) * step);
    }
  }
  return o;
}

// TlasMotionMeasure's input: a row-major 3x4 transform per origin, with `linear` (row-major 3x3) as every
// instance's rotation and scale.
std::vector<float> placed(const std::vector<float>& origins,
                          const std::array<float, 9>& linear = {1, 0, 0, 0, 1, 0, 0, 0, 1}) {
  std::vector<float> t;
  for (size_t i = 0; i + 2 < origins.size(); i += 3) {
    for (int row = 0; row < 3; ++row) {
      t.insert(t.end(), {linear[3 * row], linear[3 * row + 1], linear[3 * row + 2], origins[i + row]});
    }
  }
  return t;
}

}  // namespace

TEST_CASE("the TLAS motion measure grows when neighbours scatter and not when they move together", "[tlas][policy]") {
  const std::vector<float> base = planeOrigins(100, 1000.0f, 7);  // 10,000 instances 10 units apart
  rb::TlasMotionMeasure m;
  m.reset(placed(base));
  CHECK(m.growth(placed(base)) == 1.0);

  // The whole field translated far (a camera-relative origin shift, a convoy): every group keeps its box.
  std::vector<float> shifted = base;
  for (size_t i = 0; i < shifted.size(); i += 3) {
    shifted[i] += 5000.0f;
    shifted[i + 1] += 40.0f;
    shifted[i + 2] -= 300.0f;
  }
  CHECK(std::abs(m.growth(placed(shifted)) - 1.0) < 1e-3);

  // Each instance wanders a little (a tenth of the spacing): the boxes grow a little.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<float> small = base, large = base;
  for (size_t i = 0; i < base.size(); ++i) {
    small[i] += 1.0f * unit(rng);
    large[i] += 60.0f * unit(rng);  // six spacings: neighbours at the rebuild are now far apart
  }
  const double smallGrowth = m.growth(placed(small)), largeGrowth = m.growth(placed(large));
  INFO("small " << smallGrowth << ", large " << largeGrowth);
  CHECK(smallGrowth > 1.0);
  CHECK(smallGrowth < 1.3);
  CHECK(largeGrowth > double(rb::kDefaultTlasMaxAreaGrowth));

  // The same scatter on a field that also has height (3D cells) is seen too.
  std::vector<float> volume = base, volumeScattered;
  for (size_t i = 1; i < volume.size(); i += 3) volume[i] = float((i / 3) % 37) * 25.0f;
  m.reset(placed(volume));
  volumeScattered = volume;
  for (size_t i = 0; i < volume.size(); ++i) volumeScattered[i] += 60.0f * unit(rng);
  CHECK(m.growth(placed(volumeScattered)) > double(rb::kDefaultTlasMaxAreaGrowth));
}

TEST_CASE("the TLAS motion measure sees instances spin and grow in place", "[tlas][policy]") {
  const std::vector<float> base = planeOrigins(100, 1000.0f, 7);
  rb::TlasMotionMeasure m;
  m.reset(placed(base));
  // A quarter turn about y permutes the axes of each instance's box: the same bounds, the same area.
  CHECK(std::abs(m.growth(placed(base, {0, 0, 1, 0, 1, 0, -1, 0, 0})) - 1.0) < 1e-9);
  // An eighth of a turn widens each box by sqrt(2) in x and z: the groups' boxes grow, by less than a scatter.
  const float c = std::sqrt(0.5f);
  const double turned = m.growth(placed(base, {c, 0, c, 0, 1, 0, -c, 0, c}));
  INFO("eighth turn " << turned);
  CHECK(turned > 1.05);
  CHECK(turned < double(rb::kDefaultTlasMaxAreaGrowth));
  // Every instance three times its size where it stands: the refitted boxes would overlap their neighbours'.
  CHECK(m.growth(placed(base, {3, 0, 0, 0, 3, 0, 0, 0, 3})) > double(rb::kDefaultTlasMaxAreaGrowth));
  // A field built rotated and scaled is its own baseline.
  const std::array<float, 9> rotated = {c, 0, c, 0, 2, 0, -c, 0, c};
  m.reset(placed(base, rotated));
  CHECK(m.growth(placed(base, rotated)) == 1.0);
}

TEST_CASE("the TLAS motion measure takes degenerate lists", "[tlas][policy]") {
  rb::TlasMotionMeasure m;
  m.reset({});
  CHECK(m.growth({}) == 1.0);
  const std::vector<float> one = placed({3.0f, 4.0f, 5.0f});
  m.reset(one);
  CHECK(m.growth(one) == 1.0);
  const std::vector<float> same = placed({1, 1, 1, 1, 1, 1, 1, 1, 1});  // three instances in one point
  m.reset(same);
  CHECK(m.growth(same) == 1.0);
  CHECK(m.growth(placed({1, 1, 1, 1, 1, 1, 9, 1, 1})) > 1.0);
  // A list of another length than the one measured at the rebuild is no refit chain: no growth claimed.
  CHECK(m.growth(one) == 1.0);
  // A non-finite translation reads as unbounded growth, so the policy rebuilds rather than refits over it.
  std::vector<float> bad = placed({1, 1, 1, 1, std::numeric_limits<float>::infinity(), 1, 1, 1, 1});
  CHECK(!(m.growth(bad) <= double(rb::kDefaultTlasMaxAreaGrowth)));
}

TEST_CASE("the TLAS motion measure survives NaN, outliers, zero scale and far origins", "[tlas][policy]") {
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  const double maxGrowth = double(rb::kDefaultTlasMaxAreaGrowth);
  const std::vector<float> base = planeOrigins(100, 1000.0f, 7);
  rb::TlasMotionMeasure m;

  // A NaN in the first instance at the rebuild: the measure must not size its grid from it. Until a finite
  // list is measured again, every frame reads as unbounded growth, so the policy rebuilds.
  std::vector<float> firstNaN = base;
  firstNaN[0] = nan;
  m.reset(placed(firstNaN));
  CHECK(!(m.growth(placed(firstNaN)) <= maxGrowth));
  CHECK(!(m.growth(placed(base)) <= maxGrowth));
  // A NaN in a later instance, in a frame after a finite rebuild, is no refit either (min and max skip NaN).
  m.reset(placed(base));
  std::vector<float> laterNaN = base;
  laterNaN[3 * 4321 + 2] = nan;
  CHECK(!(m.growth(placed(laterNaN)) <= maxGrowth));
  std::vector<float> nanScale = placed(base);
  nanScale[12 * 77 + 5] = nan;  // instance 77's linear part
  CHECK(!(m.growth(nanScale) <= maxGrowth));
  CHECK(m.growth(placed(base)) == 1.0);

  // One instance far away (a skybox anchor, a parked vehicle at the origin of a streamed world) must not stretch
  // the grid so that the whole field is one group: the same scatter as above is still seen.
  std::vector<float> withOutlier = base;
  withOutlier.insert(withOutlier.end(), {1.0e6f, 0.0f, 1.0e6f});
  m.reset(placed(withOutlier));
  CHECK(m.growth(placed(withOutlier)) == 1.0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<float> scattered = withOutlier, wandered = withOutlier;
  for (size_t i = 0; i < base.size(); ++i) {
    scattered[i] += 60.0f * unit(rng);
    wandered[i] += 1.0f * unit(rng);
  }
  const double scatterGrowth = m.growth(placed(scattered)), wanderGrowth = m.growth(placed(wandered));
  INFO("with an outlier: scatter " << scatterGrowth << ", wander " << wanderGrowth);
  CHECK(scatterGrowth > maxGrowth);
  CHECK(wanderGrowth < 1.3);
  // The outlier moving on its own (it is its own group) changes nothing the tree would notice.
  std::vector<float> outlierMoved = withOutlier;
  outlierMoved[outlierMoved.size() - 3] += 5000.0f;
  CHECK(std::abs(m.growth(placed(outlierMoved)) - 1.0) < 1e-6);

  // Instances hidden by a zero scale, on one line: the baseline area is 0. Growing back is growth, not "1".
  std::vector<float> line;
  for (int i = 0; i < 40; ++i) line.insert(line.end(), {float(i) * 10.0f, 0.0f, 0.0f});
  m.reset(placed(line, {0, 0, 0, 0, 0, 0, 0, 0, 0}));
  CHECK(m.growth(placed(line, {0, 0, 0, 0, 0, 0, 0, 0, 0})) == 1.0);
  CHECK(!(m.growth(placed(line)) <= maxGrowth));

  // A field ten thousand kilometres from the origin (integer origins, exact in float there) measures as it does
  // at the origin: the boxes are summed in double, not rounded to the inputs' 1-unit spacing out there.
  std::vector<float> near, far;
  for (int z = 0; z < 60; ++z) {
    for (int x = 0; x < 60; ++x) {
      const float px = float(10 * x + (x * 7 + z) % 3), pz = float(10 * z + (z * 5 + x) % 4);
      near.insert(near.end(), {px, 0.0f, pz});
      far.insert(far.end(), {px + 1.0e7f, 0.0f, pz - 1.0e7f});
    }
  }
  const float c = std::sqrt(0.5f);
  const std::array<float, 9> eighthTurn = {c, 0, c, 0, 1, 0, -c, 0, c};
  m.reset(placed(near));
  const double nearTurned = m.growth(placed(near, eighthTurn));
  m.reset(placed(far));
  const double farTurned = m.growth(placed(far, eighthTurn));
  INFO("an eighth turn near the origin " << nearTurned << ", 10,000 km away " << farTurned);
  CHECK(nearTurned > 1.05);
  CHECK(std::abs(farTurned - nearTurned) < 1e-6);
}

TEST_CASE("an adaptive TLAS refits, rebuilds after maxRefits and when instances scatter, and traces right",
          "[as][tlas][policy]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  auto& s = *service.value();
  TestScene scene = makeConformanceScene();
  BuiltScene built = buildScene(fx, s, scene, kRebuildTlas);
  rb::TlasBuildOptions adaptive;
  adaptive.mode = rb::TlasBuildMode::Adaptive;
  adaptive.maxRefits = 3;
  auto build = [&] {
    rb::TlasInfo info;
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto t = s.recordTlasBuild(cmd, built.instances, adaptive);
      RB_REQUIRE_OK(t);
      info = t.value();
    });
    return info;
  };
  auto moveAll = [&](float dx) {
    for (size_t i = 0; i < built.instances.size(); ++i) {
      built.instances[i].transform[3] += dx;
      scene.instances[i].transform[3] += dx;
    }
  };
  const rb::AsStats before = s.stats();
  // The scene's first TLAS (buildScene) had no ALLOW_UPDATE: a rebuild, then three refits, then the count rebuilds.
  rb::TlasInfo t = build();
  CHECK(!t.updated);
  CHECK(t.areaGrowth == 1.0f);
  CHECK(t.refitsSinceRebuild == 0);
  for (uint32_t k = 1; k <= 3; ++k) {
    moveAll(0.25f);  // every instance together: the measure stays at 1
    t = build();
    CHECK(t.updated);
    CHECK(t.refitsSinceRebuild == k);
    CHECK(std::abs(t.areaGrowth - 1.0f) < 1e-4f);
  }
  t = build();
  CHECK(!t.updated);  // maxRefits reached
  const rb::AsStats after = s.stats();
  CHECK(after.tlasBuilds - before.tlasBuilds == 2);
  CHECK(after.tlasRefits - before.tlasRefits == 3);

  // One sphere flies off (the five instances are one group): the group's box more than doubles, so a rebuild.
  adaptive.maxRefits = 0;
  built.instances[1].transform[3] += 30.0f;
  scene.instances[1].transform[3] += 30.0f;
  t = build();
  CHECK(!t.updated);
  // A small step of the same sphere, further out, refits, and the refitted TLAS traces like Embree.
  built.instances[1].transform[3] += 0.5f;
  scene.instances[1].transform[3] += 0.5f;
  t = build();
  CHECK(t.updated);
  CHECK(t.areaGrowth > 1.0f);
  CHECK(t.areaGrowth < rb::kDefaultTlasMaxAreaGrowth);
  TraceComparison c = compareFirstTrace(fx, scene, t.tlas, conformanceCamera(), 96, 64);
  CHECK(double(c.hitMissAgree) / c.compared >= 0.999);
  CHECK(double(c.distanceAgree) / c.hitsCompared >= 0.999);

  // A lower threshold rebuilds on the same kind of step.
  adaptive.maxAreaGrowth = 1.0001f;
  built.instances[1].transform[3] += 2.0f;
  t = build();
  CHECK(!t.updated);

  // After a frame in another mode the measure no longer describes the chain: Adaptive rebuilds once.
  rb::TlasBuildOptions update;
  update.mode = rb::TlasBuildMode::UpdateIfPossible;
  fx.runFrame([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(s.recordTlasBuild(cmd, built.instances, update)); });
  adaptive.maxAreaGrowth = 0.0f;
  CHECK(!build().updated);
  CHECK(build().updated);
  destroyScene(fx, built);
}

TEST_CASE("bad TLAS policy options are named", "[tlas][policy][bad-input]") {
  GpuFixture fx;
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  TestScene scene = makeConformanceScene();
  BuiltScene built = buildScene(fx, *service.value(), scene);
  auto expectError = [&](const rb::TlasBuildOptions& o, const char* word) {
    fx.runFrame([&](VkCommandBuffer cmd) {
      auto t = service.value()->recordTlasBuild(cmd, built.instances, o);
      REQUIRE(!t);
      CHECK(t.error().code == rb::ErrorCode::InvalidArgument);
      INFO(t.error().message);
      CHECK(t.error().message.find(word) != std::string::npos);
    });
  };
  rb::TlasBuildOptions o;
  o.mode = rb::TlasBuildMode::Adaptive;
  o.maxAreaGrowth = 0.9f;
  expectError(o, "maxAreaGrowth");
  o.maxAreaGrowth = std::numeric_limits<float>::quiet_NaN();
  expectError(o, "maxAreaGrowth");
  o.maxAreaGrowth = 0.0f;
  o.mode = static_cast<rb::TlasBuildMode>(9);
  expectError(o, "options.mode");
  destroyScene(fx, built);
}

TEST_CASE("HybridEffects builds its TLAS as HybridEffectsDesc::tlasMode says: adaptive refits by default",
          "[tlas][policy][hybrid_effects]") {
  GpuFixture fx;
  TestScene scene = makeConformanceScene();
  EmbreeScene embree;
  addToEmbree(embree, scene);
  CpuGBuffer cpu = traceGBuffer(embree, conformanceView(64, 48));
  GpuGBuffer gbuffer(fx, cpu);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), scene, kRebuildTlas);
  // Let compaction finish first (a GPU compacts these BLASes; lavapipe skips it): a compacted BLAS has a new
  // address, which rightly makes the next TLAS a rebuild.
  for (int i = 0; i < 10; ++i) {
    const rb::AsStats st = service.value()->stats();
    if (st.blasCompacted + st.compactionsSkipped >= st.blasCount) break;
    fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(service.value()->recordPendingWork(cmd)); });
  }
  fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(service.value()->recordPendingWork(cmd)); });
  for (rb::TlasBuildMode mode : {rb::TlasBuildMode::Adaptive, rb::TlasBuildMode::Rebuild}) {
    INFO("tlasMode " << int(mode));
    rb::HybridEffectsDesc desc = rb::withPreset({}, rb::Preset::HardShadows);
    CHECK(desc.tlasMode == rb::TlasBuildMode::Adaptive);  // the default
    desc.tlasMode = mode;
    auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
    RB_REQUIRE_OK(effects);
    rb::HybridFrame frame;
    frame.gbuffer = gbuffer.desc();
    frame.instances = built.instances;  // the front end builds the TLAS
    frame.light.direction[1] = 1.0f;
    const rb::AsStats before = service.value()->stats();
    std::vector<float> first;
    for (int f = 0; f < 4; ++f) {
      fx.runAndSettle([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.value()->record(cmd, frame)); });
      const std::vector<float> shadow = readR16f(fx, effects.value()->outputs().shadow.image, 64, 48);
      if (f == 0) first = shadow;
      CHECK(shadow == first);  // a still scene: a refitted TLAS gives the same hard shadows
      CHECK(effects.value()->lastTlas().updated == (mode == rb::TlasBuildMode::Adaptive && f > 0));
    }
    const rb::AsStats after = service.value()->stats();
    CHECK(after.tlasRefits - before.tlasRefits == (mode == rb::TlasBuildMode::Adaptive ? 3u : 0u));
    CHECK(after.tlasBuilds - before.tlasBuilds == (mode == rb::TlasBuildMode::Adaptive ? 1u : 4u));
  }
  destroyScene(fx, built);
}
