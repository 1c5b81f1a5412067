// alpha: what alpha-tested (any-hit) geometry costs the shadow pass. A canopy of leaf cards over a ground, the
// cards split into interleaved chunks; the variants trace the same triangles and differ only in which chunks
// are registered MeshDesc::nonOpaque with a Mask material (0%, 10%, 50%, 100% of the triangles), against the
// all-opaque scene (opaque ray flag, no material table), hard (1 ray) and soft (4 rays) sun shadows on an
// analytic ground G-buffer. Checks that opaque variants run no any-hit shader, alpha variants do, every pixel
// traces its rays, and that shadows thin out as more cards become see-through.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "bench_images.h"
#include "foliage_scene.h"
#include "gpu_timer.h"
#include "report.h"
#include "scenarios.h"
#include "service_frames.h"

namespace rbbench {

namespace {

constexpr uint32_t kChunks = 10;           // alpha fractions in steps of 10%
constexpr double kMeanCardsCrossed = 3.0;  // per shadow ray, counting every card as opaque
constexpr float kSoftAngularRadiusDegrees = 1.0f;
constexpr uint32_t kSoftRays = rb::kDefaultSoftShadowRays;
constexpr uint32_t kGpuWidth = 2560, kGpuHeight = 1440;  // the resolution the question is asked at
constexpr float kGroundSize = 200.0f;

// Sizes of our own: lavapipe takes 15-70 us per shadow ray here (2 shared cores; a gigarays stress ray about 5 us),
// so CPU runs trace a few thousand pixels; a GPU traces the question's 2560x1440.
struct AlphaSizes {
  uint32_t cards = 0;
  uint32_t repeats = 0;  // timed recordings per variant and shadow kind
  uint32_t rounds = 1;   // over all variants, each with one warm-up recording per variant and kind
  uint32_t width = 0, height = 0;
};

AlphaSizes pickAlphaSizes(BenchEnv& env) {
  const BenchOptions& o = env.options();
  const bool cpu = env.info().isCpu;
  AlphaSizes s;
  if (o.quick) {  // smoke test: 5-10 s on lavapipe
    s.cards = 20000;
    s.repeats = 1;
    s.width = 64;
    s.height = 36;
  } else if (cpu) {  // 30-45 s on lavapipe (--full: the GPU's triangle count)
    s.cards = o.full ? 500000 : 50000;
    s.repeats = 2;
    s.rounds = 2;
    s.width = 96;
    s.height = 54;
  } else {
    s.cards = o.full ? 1000000 : 500000;
    s.repeats = 10;
    s.rounds = 2;
    s.width = kGpuWidth;
    s.height = kGpuHeight;
  }
  if (o.width) {
    s.width = o.width;
    s.height = o.height;
  }
  return s;
}

// Mean occlusion (1 - visibility) of the pass's R16F output, which is left in SHADER_READ_ONLY_OPTIMAL. For hard
// shadows it is the fraction of pixels in shadow.
double shadowedFraction(BenchEnv& env, VkImage image, uint32_t w, uint32_t h) {
  const std::vector<uint8_t> raw = readImage(env, image, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, w, h, 2,
                                             "the shadow visibility");
  double occluded = 0.0;
  for (size_t i = 0; i < size_t(w) * h; ++i) {
    uint16_t half;
    std::memcpy(&half, raw.data() + 2 * i, 2);
    occluded += 1.0 - double(halfToFloat(half));
  }
  return occluded / (double(w) * h);
}

struct Variant {
  const char* name;
  uint32_t alphaChunks;  // chunks registered non-opaque (Mask material); the others are opaque
  bool table;            // ShadowSettings::materials given
  bool merged;           // reference: every card in one opaque BLAS instead of kChunks
};

// The baseline first; the alpha variants in increasing fraction (the shadowed fraction must fall along them).
const Variant kVariants[] = {
    {"all opaque", 0, false, false},        {"0% alpha, table given", 0, true, false},
    {"10% alpha", 1, true, false},          {"50% alpha", 5, true, false},
    {"100% alpha", kChunks, true, false},   {"100% non-opaque, no table", kChunks, false, false},
    {"all opaque, 1 BLAS", 0, false, true},
};
constexpr size_t kBaseline = 0, kTableOnly = 1, kAlpha10 = 2, kAlpha50 = 3, kAlpha100 = 4, kNoTable = 5, kMerged = 6;

struct Measured {
  std::vector<double> ms;
  rb::PassStats stats;  // of a frame with exactly one recording
  double shadowed = 0.0;
};

}  // namespace

nlohmann::json runAlphaScenario(BenchEnv& env) {
  const AlphaSizes z = pickAlphaSizes(env);
  const uint64_t pixels = uint64_t(z.width) * z.height;

  // ---- the scene on the CPU ----
  FoliageView view;
  view.width = z.width;
  view.height = z.height;
  env.progress("alpha: generating " + std::to_string(z.cards) + " leaf cards");
  const AnalyticGBuffer gb = makeGroundGBuffer(view);
  const FoliageCards cards = makeFoliageCards(view, gb, z.cards, kChunks, kMeanCardsCrossed);
  const LeafTexture leaf = makeLeafTexture();
  const rbsamples::CpuMesh groundMesh = rbsamples::makeGrid(kGroundSize, 1);
  const uint64_t totalTriangles = uint64_t(cards.triangleCount()) + groundMesh.triangleCount();

  // ---- engine-side buffers and images ----
  const VkBufferUsageFlags geometryUsage = VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                           VK_BUFFER_USAGE_ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_BIT_KHR |
                                           VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  UploadedMesh ground = env.upload(groundMesh, "alpha ground");
  rb::HeadlessBuffer positions = check(env.device().createBuffer(cards.positions.size() * sizeof(float), geometryUsage,
                                                                 false, cards.positions.data()),
                                       "uploading the card positions");
  rb::HeadlessBuffer indices = check(env.device().createBuffer(cards.indices.size() * sizeof(uint32_t), geometryUsage,
                                                               false, cards.indices.data()),
                                     "uploading the card indices");
  rb::HeadlessBuffer texcoords = check(env.device().createBuffer(cards.texcoords.size() * sizeof(float),
                                                                 VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                                                                     VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                                                 false, cards.texcoords.data()),
                                       "uploading the card texture coordinates");
  SampledImage leafImage = uploadSampledImage(env, VK_FORMAT_R8G8B8A8_UNORM, VK_IMAGE_ASPECT_COLOR_BIT, leaf.width,
                                              leaf.height, leaf.rgba.data(), leaf.rgba.size(), "the leaf texture");
  SampledImage depth = uploadSampledImage(env, VK_FORMAT_D32_SFLOAT, VK_IMAGE_ASPECT_DEPTH_BIT, z.width, z.height,
                                          gb.depth.data(), gb.depth.size() * sizeof(float), "the G-buffer depth");
  SampledImage normal = uploadSampledImage(env, VK_FORMAT_R32G32B32A32_SFLOAT, VK_IMAGE_ASPECT_COLOR_BIT, z.width,
                                           z.height, gb.normal.data(), gb.normal.size() * sizeof(float),
                                           "the G-buffer normals");
  rb::GBufferDesc gbuffer;
  gbuffer.width = z.width;
  gbuffer.height = z.height;
  gbuffer.depth = {depth.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  gbuffer.normal = {normal.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  std::memcpy(gbuffer.view, gb.view, sizeof gbuffer.view);
  std::memcpy(gbuffer.projection, gb.projection, sizeof gbuffer.projection);
  for (int i = 0; i < 3; ++i) gbuffer.cameraPosition[i] = view.eye[i];

  // ---- meshes: every chunk registered twice (opaque and non-opaque: two BLASes), plus one BLAS of all cards ----
  auto service = check(rb::AccelerationStructureService::create(env.ctx()), "creating the AS service");
  auto cardDesc = [&](uint32_t firstTriangle, uint32_t triangleCount, bool nonOpaque) {
    rb::MeshDesc d;
    d.vertexAddress = positions.address;
    d.vertexBufferBytes = positions.size;
    d.vertexCount = cards.vertexCount();
    d.indexAddress = indices.address + VkDeviceSize(firstTriangle) * 3 * sizeof(uint32_t);
    d.indexBufferBytes = VkDeviceSize(triangleCount) * 3 * sizeof(uint32_t);
    d.triangleCount = triangleCount;
    d.nonOpaque = nonOpaque;
    d.texcoordAddress = texcoords.address;
    return d;
  };
  const rb::MeshHandle groundHandle = registerOrThrow(*service, ground.desc, "alpha ground");
  std::vector<rb::MeshHandle> opaqueChunks, alphaChunks;
  for (uint32_t c = 0; c < kChunks; ++c) {
    const uint32_t first = cards.chunkFirstTriangle[c], count = cards.chunkFirstTriangle[c + 1] - first;
    opaqueChunks.push_back(registerOrThrow(*service, cardDesc(first, count, false), "cards " + std::to_string(c)));
    alphaChunks.push_back(
        registerOrThrow(*service, cardDesc(first, count, true), "cards " + std::to_string(c) + " non-opaque"));
  }
  const rb::MeshHandle mergedHandle = registerOrThrow(*service, cardDesc(0, cards.triangleCount(), false), "all cards");
  env.progress("alpha: building " + std::to_string(2 * kChunks + 2) + " BLASes");
  (void)buildQueued(env, *service);
  env.runFrame([&](VkCommandBuffer cmd) { (void)check(service->recordPendingWork(cmd), "compaction frame"); });
  env.settle();

  auto table = check(rb::MaterialTable::create(env.ctx()), "creating the material table");
  rb::Material groundMaterial;
  rb::Material leafMaterial;
  leafMaterial.baseColorTexture = 0;
  leafMaterial.alphaMode = rb::AlphaMode::Mask;  // cutoff 0 = kDefaultAlphaCutoff (0.5)
  const rb::Material materials[] = {groundMaterial, leafMaterial};
  const VkImageView textures[] = {leafImage.view};
  check(table->setMaterials(materials, textures), "MaterialTable::setMaterials");

  struct Shadows {
    const char* name;
    rb::Light light;
    uint32_t raysPerPixel;
    std::unique_ptr<rb::ShadowPass> pass;
  };
  Shadows kinds[2] = {{"hard", {}, 1, nullptr}, {"soft", {}, kSoftRays, nullptr}};
  for (Shadows& k : kinds) {
    for (int i = 0; i < 3; ++i) k.light.direction[i] = float(view.toSun[i]);
    k.pass = check(rb::ShadowPass::create(env.ctx()), "creating a shadow pass");
  }
  kinds[1].light.angularRadiusDegrees = kSoftAngularRadiusDegrees;

  // ---- the variants: their instance lists and settings ----
  const size_t variantCount = std::size(kVariants);
  struct Setup {
    std::vector<rb::Instance> instances;
    rb::TlasBuildOptions tlas = kStaticTlas;
    rb::ShadowSettings settings[2];
  };
  std::vector<Setup> setups(variantCount);
  for (size_t v = 0; v < variantCount; ++v) {
    const Variant& var = kVariants[v];
    Setup& su = setups[v];
    su.instances.resize(1);
    su.instances[0].mesh = groundHandle;
    su.instances[0].material = 0;
    for (uint32_t c = 0; c < (var.merged ? 1u : kChunks); ++c) {
      rb::Instance inst;
      inst.mesh = var.merged ? mergedHandle : c < var.alphaChunks ? alphaChunks[c] : opaqueChunks[c];
      inst.material = 1;
      su.instances.push_back(inst);
    }
    for (int i = 0; i < 3; ++i) su.tlas.originOffset[i] = view.eye[i];
    su.tlas.writeShadingRecords = var.table;
    for (int k = 0; k < 2; ++k) {
      su.settings[k].raysPerPixel = kinds[k].raysPerPixel;
      su.settings[k].materials = var.table ? table.get() : nullptr;
    }
  }
  std::vector<std::array<Measured, 2>> results(variantCount);
  std::vector<uint32_t> nonOpaqueInstances(variantCount);
  // The TLAS of variant v, built into this frame's command buffer (one TLAS build per frame).
  auto buildTlas = [&](VkCommandBuffer cmd, size_t v) {
    rb::TlasInfo tlas = check(service->recordTlasBuild(cmd, setups[v].instances, setups[v].tlas), "TLAS");
    if (tlas.skippedInstances != 0) throw BenchFailure("the TLAS skipped instances whose BLAS was not built");
    nonOpaqueInstances[v] = tlas.nonOpaqueInstances;
    return tlas;
  };
  auto record = [&](VkCommandBuffer cmd, const rb::TlasInfo& tlas, size_t v, int k) {
    check(kinds[k].pass->record(
              cmd, {.gbuffer = gbuffer, .tlas = tlas, .light = kinds[k].light, .settings = setups[v].settings[k]}),
          "ShadowPass::record");
  };

  // Counting: a frame with one recording per pass gives its statistics (rays, any-hit invocations) and its
  // visibility. It also traces every variant once before any is timed.
  for (size_t v = 0; v < variantCount; ++v) {
    env.progress(std::string("alpha: counting '") + kVariants[v].name + "'");
    env.runFrame([&](VkCommandBuffer cmd) {
      rb::TlasInfo tlas = buildTlas(cmd, v);
      for (int k = 0; k < 2; ++k) record(cmd, tlas, v, k);
    });
    for (int k = 0; k < 2; ++k) {
      results[v][k].shadowed = shadowedFraction(env, kinds[k].pass->outputs().visibility, z.width, z.height);
    }
    env.settle();
    for (int k = 0; k < 2; ++k) results[v][k].stats = kinds[k].pass->stats();
  }

  // Timing, in rounds over all variants so that drift (clocks, other load) reaches every variant alike: per
  // round and variant a frame with, per pass, one warm-up recording and then recordings between timestamps (the
  // pass's own barriers order them).
  const uint32_t perRound = (z.repeats + z.rounds - 1) / z.rounds;
  GpuTimer timer(env, 4 * perRound);
  for (uint32_t round = 0; round < z.rounds; ++round) {
    env.progress("alpha: timing round " + std::to_string(round + 1) + " of " + std::to_string(z.rounds));
    for (size_t v = 0; v < variantCount; ++v) {
      const uint32_t timed = std::min(perRound, z.repeats - round * perRound);
      std::vector<std::pair<uint32_t, uint32_t>> marks[2];
      env.runFrame([&](VkCommandBuffer cmd) {
        timer.reset(cmd);
        rb::TlasInfo tlas = buildTlas(cmd, v);
        for (int k = 0; k < 2; ++k) {
          for (uint32_t i = 0; i <= timed; ++i) {
            const uint32_t a = i ? timer.mark(cmd) : 0;
            record(cmd, tlas, v, k);
            if (i) marks[k].emplace_back(a, timer.mark(cmd));
          }
        }
      });
      timer.resolve();
      for (int k = 0; k < 2; ++k) {
        for (auto [a, b] : marks[k]) results[v][k].ms.push_back(timer.ms(a, b));
      }
    }
  }
  env.settle();

  // ---- tables ----
  nlohmann::json rows = nlohmann::json::array();
  std::vector<std::string> failures;
  auto fail = [&](const std::string& m) { failures.push_back(m); };
  nlohmann::json summary = {{"cards", z.cards},
                            {"triangles", totalTriangles},
                            {"chunks", kChunks},
                            {"cardSideMetres", cards.cardSide},
                            {"leafOpenFraction", leaf.openFraction},
                            {"meanCardsCrossedIfOpaque", kMeanCardsCrossed},
                            {"repeats", z.repeats},
                            {"rounds", z.rounds}};
  for (int k = 0; k < 2; ++k) {
    const Shadows& kind = kinds[k];
    char title[256];
    std::snprintf(title, sizeof title,
                  "alpha: %s shadows (%u ray%s per pixel) through %u leaf cards (%s triangles, %u chunks), "
                  "%ux%u, median of %u in %u round%s",
                  kind.name, kind.raysPerPixel, kind.raysPerPixel == 1 ? "" : "s", z.cards,
                  humanCount(totalTriangles).c_str(), kChunks, z.width, z.height, z.repeats, z.rounds,
                  z.rounds == 1 ? "" : "s");
    Table t(title, {{"variant", "variant"},
                    {"alpha tris", "alphaFraction", 2},
                    {"non-opaque inst", "nonOpaqueInstances"},
                    {"any-hit on", "alphaTested"},
                    {"median ms", "medianMs", 3},
                    {"min ms", "minMs", 3},
                    {"rays", "rays"},
                    {"Mrays/s", "mraysPerSecond", 2},
                    {"any-hit/ray", "anyHitPerRay", 3},
                    {"shadowed", "shadowedFraction", 4},
                    {"vs opaque", "ratioToOpaque", 3}});
    const double baseMs = median(results[kBaseline][k].ms);
    const uint64_t expectedRays = pixels * kind.raysPerPixel;
    for (size_t v = 0; v < variantCount; ++v) {
      const Variant& var = kVariants[v];
      const Measured& m = results[v][k];
      const double med = median(m.ms);
      const uint64_t alphaTriangles =
          var.merged ? 0 : uint64_t(cards.chunkFirstTriangle[var.alphaChunks]) - cards.chunkFirstTriangle[0];
      const bool alphaTested = var.table && nonOpaqueInstances[v] > 0;
      nlohmann::json row = {{"shadows", kind.name},
                            {"raysPerPixel", kind.raysPerPixel},
                            {"variant", var.name},
                            {"alphaChunks", var.alphaChunks},
                            {"alphaTriangles", alphaTriangles},
                            {"alphaFraction", double(alphaTriangles) / double(totalTriangles)},
                            {"materialTable", var.table},
                            {"mergedBlas", var.merged},
                            {"nonOpaqueInstances", nonOpaqueInstances[v]},
                            {"alphaTested", alphaTested},
                            {"medianMs", med},
                            {"minMs", minimum(m.ms)},
                            {"allMs", m.ms},
                            {"passStatsGpuMs", m.stats.gpuMs},
                            {"rays", m.stats.rays},
                            {"mraysPerSecond", med > 0 ? double(m.stats.rays) / (med * 1e-3) * 1e-6 : 0.0},
                            {"anyHitInvocations", m.stats.anyHitInvocations},
                            {"anyHitPerRay", ratio(double(m.stats.anyHitInvocations), double(m.stats.rays))},
                            {"shadowedFraction", m.shadowed},
                            {"ratioToOpaque", ratio(med, baseMs)}};
      t.add(row);
      rows.push_back(row);

      const std::string what = std::string(kind.name) + " '" + var.name + "': ";
      if (m.stats.frame == 0) fail(what + "the pass resolved no statistics");
      if (m.stats.rays != expectedRays) {
        fail(what + std::to_string(m.stats.rays) + " rays, expected " + std::to_string(expectedRays) +
             " (every ground pixel traces)");
      }
      if (alphaTested && m.stats.anyHitInvocations == 0) fail(what + "alpha-tested but no any-hit invocations");
      if (!alphaTested && m.stats.anyHitInvocations != 0) {
        fail(what + std::to_string(m.stats.anyHitInvocations) + " any-hit invocations where every ray is opaque");
      }
      if (var.alphaChunks != (var.merged ? 0 : nonOpaqueInstances[v])) {
        fail(what + std::to_string(nonOpaqueInstances[v]) + " non-opaque instances, expected " +
             std::to_string(var.alphaChunks));
      }
    }
    t.print();

    // Shadows: the opaque variants cast the same shadow; see-through cards let more light through, step by step.
    // Hard shadows are deterministic (strictly fewer shadowed pixels at each step). Soft ones are jittered per
    // frame, so they agree within noise: a pixel's 4-ray mean has variance <= 1/16, the difference of two frames'
    // means over all pixels a standard deviation <= sqrt(2 / 16 / pixels); allowed 5 of them.
    const bool soft = kind.raysPerPixel > 1;
    const double noise = soft ? 5.0 * std::sqrt(2.0 / 16.0 / double(pixels)) : 0.0;
    const double same = soft ? noise : 1e-3;
    auto shadowed = [&](size_t v) { return results[v][k].shadowed; };
    auto name = [&](size_t v) { return std::string(" with '") + kVariants[v].name + "'"; };
    if (shadowed(kBaseline) < 0.5) {
      fail(std::string(kind.name) + ": the canopy shadows only " + std::to_string(shadowed(kBaseline)) +
           " of the ground (expected most of it)");
    }
    for (size_t v : {kTableOnly, kNoTable, kMerged}) {
      if (std::fabs(shadowed(v) - shadowed(kBaseline)) > same) {
        fail(std::string(kind.name) + ": shadowed fraction " + std::to_string(shadowed(v)) + name(v) + " but " +
             std::to_string(shadowed(kBaseline)) + name(kBaseline));
      }
    }
    const size_t order[] = {kBaseline, kAlpha10, kAlpha50, kAlpha100};
    for (size_t i = 1; i < std::size(order); ++i) {
      const size_t a = order[i - 1], b = order[i];
      if (!(shadowed(b) < shadowed(a) + noise)) {
        fail(std::string(kind.name) + ": shadowed fraction " + std::to_string(shadowed(b)) + name(b) +
             " is not below " + std::to_string(shadowed(a)) + name(a));
      }
    }
    if (soft && !(shadowed(kAlpha100) < shadowed(kBaseline) - noise)) {
      fail(std::string(kind.name) + ": shadowed fraction " + std::to_string(shadowed(kAlpha100)) + name(kAlpha100) +
           " is not clearly below " + std::to_string(shadowed(kBaseline)) + name(kBaseline));
    }
    std::printf("  shadowed fraction: opaque %.4f > 10%% %.4f > 50%% %.4f > 100%% %.4f\n", shadowed(kBaseline),
                shadowed(kAlpha10), shadowed(kAlpha50), shadowed(kAlpha100));
    auto msRatio = [&](size_t v) { return ratio(median(results[v][k].ms), baseMs); };
    const std::string n = kind.name;
    summary[n + "OpaqueMs"] = baseMs;
    summary[n + "TableOnlyOverOpaque"] = msRatio(kTableOnly);
    summary[n + "Alpha10OverOpaque"] = msRatio(kAlpha10);
    summary[n + "Alpha50OverOpaque"] = msRatio(kAlpha50);
    summary[n + "Alpha100OverOpaque"] = msRatio(kAlpha100);
    summary[n + "NonOpaqueNoTableOverOpaque"] = msRatio(kNoTable);
    summary[n + "MergedBlasOverOpaque"] = msRatio(kMerged);
    const rb::PassStats& full = results[kAlpha100][k].stats;
    summary[n + "AnyHitPerRayAt100"] = ratio(double(full.anyHitInvocations), double(full.rays));
  }
  summary["sanityChecks"] = failures.empty() ? "passed" : "failed";
  printSummary(summary);

  // ---- teardown ----
  for (Shadows& k : kinds) k.pass.reset();
  table.reset();
  check(env.device().waitIdle(), "vkDeviceWaitIdle");
  env.settle();
  service.reset();
  destroySampledImage(env, leafImage);
  destroySampledImage(env, depth);
  destroySampledImage(env, normal);
  env.destroy(ground);
  env.device().destroyBuffer(positions);
  env.device().destroyBuffer(indices);
  env.device().destroyBuffer(texcoords);
  if (!failures.empty()) {
    std::string all = failures.front();
    for (size_t i = 1; i < failures.size(); ++i) all += "; " + failures[i];
    throw BenchFailure("alpha sanity checks: " + all);
  }
  return {{"width", z.width},
          {"height", z.height},
          {"cards", z.cards},
          {"triangles", totalTriangles},
          {"softAngularRadiusDegrees", kSoftAngularRadiusDegrees},
          {"rows", rows},
          {"summary", summary}};
}

}  // namespace rbbench
