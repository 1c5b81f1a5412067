// Change resets (hybrid_effects.h, "Change resets"; issue 29): when HybridEffects sees an instance move, it restarts
// the denoisers' history where the move can have changed the effect, and nowhere else. A box of the conformance
// scene jumps; the shadow and AO masks the front end writes are compared with the same footprints computed here on
// the CPU from the Embree G-buffer (every pixel inside a narrower footprint is set, none outside a wider one), and
// the denoisers' history lengths show that exactly the masked (and disoccluded) pixels started afresh.
#include <catch2/catch_test_macros.hpp>

#include <glm/glm.hpp>
#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "raybridge_shader_interface.glsl"
#include "synthetic_gbuffer.h"

using namespace rbtest;

namespace {

constexpr uint32_t kW = 96, kH = 72;
constexpr uint32_t kStillFrames = 4;  // frames with the box at its first place
constexpr float kAoRange = 1.0f;
constexpr float kSunDegrees = 2.0f;
const glm::dvec3 kSun = glm::normalize(glm::dvec3(0.5, 0.8, -0.4));  // towards the light
const glm::dvec3 kSunUp(0.0, 1.0, 0.0);  // rb::Light's default: axis-aligned, the slab test's zero components

SyntheticView view() { return motionTestView(kW, kH); }

struct World {
  TestScene scene;
  EmbreeScene embree;
  CpuGBuffer cpu;
  explicit World(float x, float z) : scene(makeConformanceScene()) {
    scene.instances[3].transform = translation(x, 1.2f, z);  // instance 3: a box
    addToEmbree(embree, scene);
    cpu = traceGBuffer(embree, view());
  }
};

// The world box of instance `i` (its mesh's vertices under its transform).
struct Box {
  glm::dvec3 lo{1e300}, hi{-1e300};
};
Box worldBox(const TestScene& s, uint32_t i) {
  const rbsamples::CpuMesh& m = s.meshes[s.instances[i].mesh];
  const auto& t = s.instances[i].transform;
  Box b;
  for (size_t v = 0; v < m.positions.size(); v += 3) {
    glm::dvec3 p;
    for (int r = 0; r < 3; ++r)
      p[r] = t[r * 4 + 0] * m.positions[v] + t[r * 4 + 1] * m.positions[v + 1] + t[r * 4 + 2] * m.positions[v + 2] +
             t[r * 4 + 3];
    b.lo = glm::min(b.lo, p);
    b.hi = glm::max(b.hi, p);
  }
  return b;
}

double distanceTo(const Box& b, const glm::dvec3& p) {
  return glm::length(glm::max(glm::max(b.lo - p, p - b.hi), glm::dvec3(0.0)));
}

// Whether the ray p + t * d (t >= 0) meets the box grown by `grow`.
bool rayHits(const Box& b, double grow, const glm::dvec3& p, const glm::dvec3& d) {
  double enter = 0.0, leave = 1e300;
  for (int k = 0; k < 3; ++k) {
    const double lo = b.lo[k] - grow, hi = b.hi[k] + grow;
    if (std::abs(d[k]) < 1e-12) {
      if (p[k] < lo || p[k] > hi) return false;
      continue;
    }
    double t0 = (lo - p[k]) / d[k], t1 = (hi - p[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
  }
  return enter <= leave;
}

// The shadow footprint of the boxes at pixel position p: in a box, or its ray to the sun crosses one widened by the
// soft light's spread (tan(angle) * the distance to the box's far side, as change_masks.comp) scaled by `spread`,
// plus `pad`.
bool inShadowFootprint(const std::vector<Box>& boxes, const glm::dvec3& p, const glm::dvec3& sun, double spread,
                       double pad) {
  for (const Box& b : boxes) {
    const glm::dvec3 centre = 0.5 * (b.lo + b.hi);
    const double reach = glm::length(centre - p) + glm::length(b.hi - centre);
    const double widen = spread * std::tan(kSunDegrees * M_PI / 180.0) * reach + pad;
    if (distanceTo(b, p) <= pad || rayHits(b, widen, p, sun)) return true;
  }
  return false;
}

// Seen through box b: the segment from p to the camera crosses it, grown by `grow` (negative: shrunk).
bool seenThrough(const Box& b, double grow, const glm::dvec3& p) {
  const glm::dvec3 toEye = view().eye - p;
  return rayHits(b, grow, p, glm::normalize(toEye)) && distanceTo(b, view().eye) > 0.0;
}

bool inAoFootprint(const std::vector<Box>& boxes, const glm::dvec3& p, double range) {
  for (const Box& b : boxes)
    if (distanceTo(b, p) <= range) return true;
  return false;
}

std::vector<float> readR8(GpuFixture& fx, const rb::EffectImage& image) {
  std::vector<uint8_t> raw = readPassImage(fx, image.image, image.width, image.height, 1);
  std::vector<float> out(raw.size());
  for (size_t i = 0; i < raw.size(); ++i) out[i] = raw[i] / 255.0f;
  return out;
}

struct Run {
  std::vector<float> shadowMask, aoMask, shadowFrames, aoFrames;
  // The frame after the change (nothing moves): its follow-up masks and histories.
  std::vector<float> shadowFollowMask, aoFollowMask, shadowFollowFrames, aoFollowFrames;
  bool stillFrameHadMask = true;
};

// kStillFrames frames of `before`, then one of `after`, through HybridEffects (soft shadows and AO at 4 rays,
// denoised, anti-lag off so that only disocclusion and change resets restart a pixel).
Run run(GpuFixture& fx, const World& before, const World& after, bool changeResets, const glm::dvec3& sun = kSun) {
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), before.scene);
  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectShadows | rb::kEffectAo;
  desc.shadows.raysPerPixel = 4;
  desc.ao.raysPerPixel = 4;
  desc.ao.range = kAoRange;
  desc.ao.schedule.halfResolution = false;
  desc.denoiser.disableAntiLag = true;
  desc.disableChangeResets = !changeResets;
  auto fxs = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
  RB_REQUIRE_OK(fxs);
  rb::HybridEffects& effects = *fxs.value();
  Run out;
  for (uint32_t f = 0; f <= kStillFrames + 1; ++f) {
    const World& w = f < kStillFrames ? before : after;
    std::vector<rb::Instance> instances = built.instances;
    for (size_t i = 0; i < instances.size(); ++i)
      std::copy(w.scene.instances[i].transform.begin(), w.scene.instances[i].transform.end(), instances[i].transform);
    GpuGBuffer gbuffer(fx, w.cpu);
    rb::HybridFrame frame;
    frame.gbuffer = gbuffer.desc();
    frame.instances = instances;
    frame.light.direction[0] = float(sun.x);
    frame.light.direction[1] = float(sun.y);
    frame.light.direction[2] = float(sun.z);
    frame.light.angularRadiusDegrees = kSunDegrees;
    fx.runFrame([&](VkCommandBuffer cmd) { RB_REQUIRE_OK(effects.record(cmd, frame)); });
    if (f == kStillFrames - 1) {
      out.stillFrameHadMask = effects.changeMask(rb::kEffectShadows).image != VK_NULL_HANDLE ||
                              effects.changeMask(rb::kEffectAo).image != VK_NULL_HANDLE;
    }
    if (f == kStillFrames) {
      if (changeResets) {
        REQUIRE(effects.changeMask(rb::kEffectShadows).image != VK_NULL_HANDLE);
        REQUIRE(effects.changeMask(rb::kEffectAo).image != VK_NULL_HANDLE);
        out.shadowMask = readR8(fx, effects.changeMask(rb::kEffectShadows));
        out.aoMask = readR8(fx, effects.changeMask(rb::kEffectAo));
      } else {
        CHECK(effects.changeMask(rb::kEffectShadows).image == VK_NULL_HANDLE);
      }
      out.shadowFrames = historyFrames(fx, *effects.shadowDenoiser());
      out.aoFrames = historyFrames(fx, *effects.aoDenoiser());
    }
    if (f == kStillFrames + 1 && changeResets) {
      REQUIRE(effects.changeMask(rb::kEffectShadows).image != VK_NULL_HANDLE);
      out.shadowFollowMask = readR8(fx, effects.changeMask(rb::kEffectShadows));
      out.aoFollowMask = readR8(fx, effects.changeMask(rb::kEffectAo));
      out.shadowFollowFrames = historyFrames(fx, *effects.shadowDenoiser());
      out.aoFollowFrames = historyFrames(fx, *effects.aoDenoiser());
    }
  }
  (void)fx.device().waitIdle();
  fxs.value().reset();
  destroyScene(fx, built);
  return out;
}

}  // namespace

TEST_CASE("a moved instance resets history only inside its old and new footprint", "[denoise][motion][changes]") {
  GpuFixture fx;
  const World before(-1.0f, 1.0f), after(1.5f, 2.0f);
  const std::vector<Box> boxes = {worldBox(before.scene, 3), worldBox(after.scene, 3)};
  const Run on = run(fx, before, after, true);
  CHECK_FALSE(on.stillFrameHadMask);  // frames without a change write no mask

  // The masks against the footprints computed here: all of a narrower one set, nothing outside a wider one.
  uint32_t shadowSet = 0, aoSet = 0, shadowMissed = 0, aoMissed = 0, shadowStray = 0, aoStray = 0, surface = 0;
  for (size_t i = 0; i < size_t(kW) * kH; ++i) {
    if (!after.cpu.hit[i]) {
      CHECK(on.shadowMask[i] == 0.0f);  // the sky has no history to reset
      continue;
    }
    ++surface;
    const glm::dvec3 p = after.cpu.position[i];
    const double pad = 1e-3 * glm::length(p - view().eye);
    const bool shadow = on.shadowMask[i] > 0.5f, ao = on.aoMask[i] > 0.5f;
    shadowSet += shadow;
    aoSet += ao;
    shadowMissed += !shadow && inShadowFootprint(boxes, p, kSun, 0.9, 0.0);
    shadowStray += shadow && !inShadowFootprint(boxes, p, kSun, 1.1, 3.0 * pad + 0.01);
    aoMissed += !ao && inAoFootprint(boxes, p, kAoRange * 0.99);
    aoStray += ao && !inAoFootprint(boxes, p, kAoRange * 1.01 + 3.0 * pad + 0.01);
  }
  std::printf("change masks: shadows %u, AO %u of %u surface pixels; missed %u / %u, stray %u / %u\n", shadowSet, aoSet,
              surface, shadowMissed, aoMissed, shadowStray, aoStray);
  // Where the box was reveals what it hid (RB_CHANGE_REVEALS): the pixels seen through its old box and not changed
  // are marked at the follow-up level (reset rays, history kept), all of a narrower footprint, none outside a wider.
  const float followUp = std::round(RB_REACTIVE_FOLLOW_UP_VALUE * 255.0) / 255.0f;
  uint32_t revealed = 0, revealMissed = 0, revealStray = 0;
  for (size_t i = 0; i < size_t(kW) * kH; ++i) {
    if (!after.cpu.hit[i]) continue;
    const glm::dvec3 p = after.cpu.position[i];
    const double pad = 1e-3 * glm::length(p - view().eye);
    for (const std::vector<float>* mask : {&on.shadowMask, &on.aoMask}) {
      const float m = (*mask)[i];
      revealed += m == followUp;
      revealMissed += m <= 0.5f && m != followUp && seenThrough(boxes[0], -0.01, p);
      revealStray += m == followUp && !seenThrough(boxes[0], 3.0 * pad + 0.01, p);
      CHECK((m == 0.0f || m == followUp || m == 1.0f));
    }
  }
  std::printf("revealed: %u follow-up marks, missed %u, stray %u\n", revealed, revealMissed, revealStray);
  CHECK(revealed > 20);
  CHECK(revealMissed == 0);
  CHECK(revealStray == 0);
  CHECK(shadowSet > 50);  // the box and both of its shadows are in view
  CHECK(aoSet > 50);
  CHECK(shadowSet < surface / 2);  // and most of the image is not
  CHECK(aoSet < surface / 2);
  CHECK(shadowMissed == 0);
  CHECK(aoMissed == 0);
  CHECK(shadowStray == 0);
  CHECK(aoStray == 0);

  // The history: a masked pixel starts afresh, at kDefaultResetRaysFactor frames (HybridEffects traced that many
  // times the rays there: RaySchedule::resetRays); an unmasked one keeps its history unless disoccluded (the surface
  // there is another one than last frame's: the box's old place, its new place), and adds that many frames where
  // marked at the follow-up level. A disoccluded follow-up pixel starts from the reset rays' frames, not one.
  const float restartFrames = float(rb::kDefaultResetRaysFactor);
  auto check = [&](const std::vector<float>& mask, const std::vector<float>& frames, const char* what) {
    uint32_t reset = 0, kept = 0, strayResets = 0, maskedKept = 0, revealedNew = 0, revealedNewWrong = 0;
    for (size_t i = 0; i < size_t(kW) * kH; ++i) {
      if (!after.cpu.hit[i]) continue;
      const bool disoccluded = !before.cpu.hit[i] || before.cpu.instance[i] != after.cpu.instance[i] ||
                               glm::length(before.cpu.position[i] - after.cpu.position[i]) > 1e-3;
      const bool follow = mask[i] == followUp;
      if (mask[i] > 0.5f) {
        maskedKept += frames[i] != restartFrames;
        ++reset;
      } else if (!disoccluded) {
        strayResets += frames[i] != float(kStillFrames) + (follow ? restartFrames : 1.0f);
        ++kept;
      } else if (follow) {
        revealedNew += 1;
        revealedNewWrong += frames[i] != restartFrames;
      }
    }
    std::printf("%s history: %u masked pixels restarted (%u did not), %u kept (%u did not), %u revealed afresh "
                "(%u not at the reset rays' frames)\n",
                what, reset, maskedKept, kept, strayResets, revealedNew, revealedNewWrong);
    CHECK(maskedKept == 0);
    CHECK(strayResets == 0);
    CHECK(kept > reset);
    CHECK(revealedNew > 0);
    CHECK(revealedNewWrong == 0);
  };
  check(on.shadowMask, on.shadowFrames, "shadow");
  check(on.aoMask, on.aoFrames, "AO");

  // The frame after (kDefaultResetFollowUpFrames > 0, nothing moves): the same pixels are marked at the follow-up
  // level and nothing else; they traced the reset rays again and add that many frames to the history they kept.
  static_assert(rb::kDefaultResetFollowUpFrames > 0);
  auto checkFollowUp = [&](const std::vector<float>& mask, const std::vector<float>& frames,
                           const std::vector<float>& followMask, const std::vector<float>& followFrames,
                           const char* what) {
    uint32_t marked = 0, wrongMark = 0, wrongFrames = 0;
    for (size_t i = 0; i < size_t(kW) * kH; ++i) {
      const bool changed = mask[i] > 0.5f || mask[i] == followUp;  // restarted, or revealed
      marked += changed;
      wrongMark += followMask[i] != (changed ? followUp : 0.0f);
      if (after.cpu.hit[i]) wrongFrames += followFrames[i] != frames[i] + (changed ? restartFrames : 1.0f);
    }
    std::printf("%s follow-up: %u pixels, %u marked otherwise, %u histories otherwise\n", what, marked, wrongMark,
                wrongFrames);
    CHECK(marked > 50);
    CHECK(wrongMark == 0);
    CHECK(wrongFrames == 0);
  };
  checkFollowUp(on.shadowMask, on.shadowFrames, on.shadowFollowMask, on.shadowFollowFrames, "shadow");
  checkFollowUp(on.aoMask, on.aoFrames, on.aoFollowMask, on.aoFollowFrames, "AO");

  // Without change resets (and anti-lag off) the same pixels keep their history: the restarts above are the masks'.
  const Run off = run(fx, before, after, false);
  uint32_t restartedOff = 0, restartedOn = 0;
  for (size_t i = 0; i < size_t(kW) * kH; ++i) {
    restartedOff += after.cpu.hit[i] && off.aoFrames[i] < float(kStillFrames + 1);
    restartedOn += after.cpu.hit[i] && on.aoFrames[i] < float(kStillFrames + 1);
  }
  CHECK(restartedOn > restartedOff + 50);
}

TEST_CASE("a sun straight overhead casts the moved box's shadow footprint too", "[denoise][motion][changes]") {
  GpuFixture fx;
  const World before(-1.0f, 1.0f), after(1.5f, 2.0f);
  const std::vector<Box> boxes = {worldBox(before.scene, 3), worldBox(after.scene, 3)};
  const Run on = run(fx, before, after, true, kSunUp);
  uint32_t set = 0, missed = 0, stray = 0, under = 0;
  for (size_t i = 0; i < size_t(kW) * kH; ++i) {
    if (!after.cpu.hit[i]) continue;
    const glm::dvec3 p = after.cpu.position[i];
    const double pad = 1e-3 * glm::length(p - view().eye);
    const bool shadow = on.shadowMask[i] > 0.5f;
    set += shadow;
    missed += !shadow && inShadowFootprint(boxes, p, kSunUp, 0.9, 0.0);
    stray += shadow && !inShadowFootprint(boxes, p, kSunUp, 1.1, 3.0 * pad + 0.01);
    // The ground straight under either box: in its shadow, outside the box itself.
    for (const Box& b : boxes)
      under += shadow && p.y < b.lo.y && p.x > b.lo.x && p.x < b.hi.x && p.z > b.lo.z && p.z < b.hi.z;
  }
  std::printf("change mask, sun overhead: shadows %u set, %u under the boxes; missed %u, stray %u\n", set, under,
              missed, stray);
  CHECK(under > 10);
  CHECK(missed == 0);
  CHECK(stray == 0);
}

TEST_CASE("engine change boxes that are not finite or inverted are refused by name, nothing recorded",
          "[hybrid_effects][changes][errors]") {
  GpuFixture fx;
  const World w(-1.0f, 1.0f);
  auto service = rb::AccelerationStructureService::create(fx.ctx());
  RB_REQUIRE_OK(service);
  BuiltScene built = buildScene(fx, *service.value(), w.scene);
  rb::HybridEffectsDesc desc;
  desc.effects = rb::kEffectAo;
  auto effects = rb::HybridEffects::create(fx.ctx(), service.value().get(), desc);
  RB_REQUIRE_OK(effects);
  GpuGBuffer gbuffer(fx, w.cpu);
  rb::ChangedBox bad[2];
  bad[1].min[1] = 2.0;  // min above max on y
  bad[1].max[1] = 1.0;
  rb::ChangedBox nan;
  nan.max[2] = std::nan("");
  for (std::span<const rb::ChangedBox> boxes :
       {std::span<const rb::ChangedBox>(bad, 2), std::span<const rb::ChangedBox>(&nan, 1)}) {
    rb::HybridFrame frame;
    frame.gbuffer = gbuffer.desc();
    frame.instances = built.instances;
    frame.changedBoxes = boxes;
    auto cmd = fx.device().beginCommands();
    RB_REQUIRE_OK(cmd);
    fx.ctx().beginFrame();
    rb::Status st = effects.value()->record(cmd.value(), frame);
    REQUIRE_FALSE(st);
    const std::string m = st.error().message;
    INFO(m);
    CHECK(m.find("changedBoxes[") != std::string::npos);
    CHECK(m.find("min <= max") != std::string::npos);
    RB_REQUIRE_OK(fx.device().submitAndWait(cmd.value()));
  }
  effects.value().reset();
  destroyScene(fx, built);
}
