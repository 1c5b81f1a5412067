// The effects front end (hybrid_effects.h): passes and denoisers of the enabled effects, recorded in order.
#include <raybridge/hybrid_effects.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "change_masks.h"
#include "change_tracker.h"
#include "changed_box.h"
#include "context_impl.h"
#include "effect_budget.h"
#include "effect_schedule.h"
#include "hybrid_effects_validation.h"
#include "light_validation.h"
#include "neutral_images.h"
#include "pass_constants.h"
#include "ray_schedule_stage.h"
#include "scene_lighting_resolve.h"

namespace rb {

namespace {

Error invalid(std::string message) {
  return {ErrorCode::InvalidArgument, VK_SUCCESS, "HybridEffects: " + std::move(message)};
}

Error wrap(const char* what, const Error& e) {
  Error out = e;
  out.message = std::string("HybridEffects: ") + what + ": " + e.message;
  return out;
}

// The frame's lighting as reflection hits see it: the pass lights hits by one directional light, the frame's; a
// local one leaves them to the sky.
SceneLighting reflectionLighting(const HybridFrame& f) {
  SceneLighting l = f.lighting;
  l.noSun = f.light.type != LightType::Directional;
  for (int i = 0; i < 3; ++i) l.sunDirection[i] = l.noSun ? 0.0f : f.light.direction[i];
  return l;
}

bool hasSize(const Light& l) {
  return l.type == LightType::Directional ? l.angularRadiusDegrees > 0.0f : l.radius > 0.0f;
}

// The light as the shadow pass traces it and the rays per pixel (see ShadowEffectSettings).
struct ShadowPlan {
  Light light;
  uint32_t rays = 1;
  bool soft = false;  // rays sample the light's disk (noisy: denoised)
};

ShadowPlan planShadows(const ShadowEffectSettings& s, const Light& frameLight) {
  ShadowPlan p{frameLight, 1, false};
  const bool directional = frameLight.type == LightType::Directional;
  if (directional && s.softAngularRadiusDegrees > 0.0f) p.light.angularRadiusDegrees = s.softAngularRadiusDegrees;
  uint32_t rays = s.raysPerPixel ? s.raysPerPixel : (hasSize(p.light) ? kDefaultSoftShadowRays : 1u);
  if (rays == 1 && !(directional && s.softAngularRadiusDegrees > 0.0f)) {
    p.light.angularRadiusDegrees = 0.0f, p.light.radius = 0.0f;  // one ray = hard, unless a disk is asked for
  } else if (rays > 1 && !hasSize(p.light)) {
    if (directional) p.light.angularRadiusDegrees = kDefaultSoftLightAngularRadiusDegrees;
    else
      rays = 1;  // a point or spot light without a radius stays hard
  }
  p.rays = rays;
  p.soft = hasSize(p.light);
  return p;
}

EffectImage image(VkImage i, VkImageView v, VkFormat f, VkImageLayout layout, uint32_t w, uint32_t h) {
  return {i, v, f, layout, w, h};
}

EffectImage image(const GpuImage& i) {
  return {i.image, i.view, i.format, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, i.width, i.height};
}

bool sameImages(const EffectImage& a, const EffectImage& b) {
  return a.image == b.image && a.view == b.view && a.width == b.width && a.height == b.height;
}

// Whether the shadow effect is soft for any light the frame may bring (so its denoiser is made with the outputs);
// "the light decides" (0 rays) stays undecided until a frame brings a light with a size.
bool shadowsSoftByDesc(const ShadowEffectSettings& s) {
  return !s.disableDenoiser && (s.raysPerPixel > 1 || s.softAngularRadiusDegrees > 0.0f);
}

template <typename T>
PassStats statsOf(const std::unique_ptr<T>& p) {
  return p ? p->stats() : PassStats{};
}

// Creates `slot` when wanted and missing, retires it (deferred release) when not wanted.
template <typename T, typename Create>
Status ensure(std::unique_ptr<T>& slot, bool wanted, const char* what, Create create) {
  if (!wanted) {
    slot.reset();
    return {};
  }
  if (slot) return {};
  auto made = create();
  if (!made) return wrap(what, made.error());
  slot = std::move(made.value());
  return {};
}

}  // namespace

struct HybridEffects::Impl {
  Context& ctx;
  AccelerationStructureService* service = nullptr;
  HybridEffectsDesc desc;
  // memoryByEffect(): the Context's memory owners of each effect and of what they share. Every entry point holds the
  // shared one (MemoryOwnerScope), and the work of one effect its own. Released by ~Impl: the Context gives them out
  // again once what the members retire is freed.
  enum Owner : uint8_t { kOwnShadows, kOwnAo, kOwnReflections, kOwnLocalLights, kOwnShared, kOwnerCount };
  uint32_t owners[kOwnerCount] = {};
  MemoryOwnerScope own(Owner o) { return MemoryOwnerScope(internal::contextImpl(ctx), owners[o]); }
  std::unique_ptr<ShadowPass> shadow;
  std::unique_ptr<Denoiser> shadowDenoiser;
  std::unique_ptr<AoPass> ao;
  std::unique_ptr<Denoiser> aoDenoiser;
  std::unique_ptr<ReflectionPass> reflection;
  std::unique_ptr<ManyLightPass> localLights;
  // The frame's local lights, uploaded once and read by the many-light pass and the reflection hits.
  std::unique_ptr<LightList> lightList;
  std::unique_ptr<Denoiser> localLightDenoiser;
  std::unique_ptr<Denoiser> reflectionDenoiser;
  // The denoisers' transient images, one set for all of them (recorded one after another into one command buffer):
  // made for the first denoiser at the frame's size, under the shared memory owner; gone with the last denoiser.
  std::unique_ptr<DenoiserScratch> denoiserScratch;
  uint32_t frameWidth = 0, frameHeight = 0;  // the latest record()'s G-buffer
  // The engine's materials, shared by every pass: reflection hits shade with them, and shadow, AO and
  // reflection rays alpha-test non-opaque geometry with them. The table (GPU memory) exists only while a pass
  // does; the engine's last setMaterials is kept here to fill it when one is created.
  std::unique_ptr<MaterialTable> materials;
  std::vector<Material> materialData;
  std::vector<VkImageView> textureData;
  bool haveMaterialData = false;

  Status syncMaterialTable() {
    if (!shadow && !ao && !reflection && !localLights) {
      materials.reset();  // retired to the Context like the passes
      return {};
    }
    if (materials) return {};
    auto table = MaterialTable::create(ctx);
    if (!table) return wrap("MaterialTable::create", table.error());
    if (haveMaterialData) {
      if (Status st = table.value()->setMaterials(materialData, textureData); !st)
        return wrap("MaterialTable::setMaterials", st.error());
    }
    materials = std::move(table.value());
    return {};
  }
  HybridOutputs outputs;
  TlasInfo tlas;
  NeutralImages neutral;  // what outputs() names for an effect that is off (or not sized yet)
  // Change resets (hybrid_effects.h): this frame's known changes and the masks made of them.
  ChangeTracker changes;
  ChangeMasks changeMasks;
  // This frame's changed local lights as the reflection rays test them (ReflectionSettings::relitBoxes).
  std::vector<ChangedBox> reflectionRelit;
  std::vector<AccelerationStructureService::MeshChange> meshChanges;
  std::vector<GpuChangeBox> gpuChangeBoxes;
  EffectBudget budget;  // HybridEffectsDesc::budgetMs, and the hook's timestamps (HybridStats::hook)

  Impl(Context& c, AccelerationStructureService* s) : ctx(c), service(s) {
    for (uint32_t& id : owners) id = internal::contextImpl(ctx).newMemoryOwner();
  }
  ~Impl() {
    neutral.retire(ctx);
    changeMasks.retire(ctx);
    budget.retire(ctx);
    for (uint32_t id : owners) internal::contextImpl(ctx).releaseMemoryOwner(id);
  }

  // The masks to write: one per effect whose denoiser exists (the readers of a history).
  uint32_t changeMaskEffects() const {
    if (desc.disableChangeResets) return 0u;
    return (shadowDenoiser ? RB_CHANGE_SHADOWS : 0u) | (aoDenoiser ? RB_CHANGE_AO : 0u) |
           (localLightDenoiser ? RB_CHANGE_LOCAL_LIGHTS : 0u) | (reflectionDenoiser ? RB_CHANGE_REFLECTIONS : 0u);
  }
  Status recordTlas(VkCommandBuffer cmd, const HybridFrame& frame);
  Status recordChanges(VkCommandBuffer cmd, const HybridFrame& f, bool trackInstances);

  // The denoiser of one signal: created when wanted (with the outputs, so its output is named from create() on,
  // or by record()), retired when not.
  Status ensureDenoiser(std::unique_ptr<Denoiser>& slot, bool wanted, DenoiseSignal kind, const char* what) {
    DenoiserDesc dd;
    dd.signal = kind;
    return ensure(slot, wanted, what, [&] { return Denoiser::create(ctx, dd); });
  }

  // Allocates every enabled output at desc.width x desc.height (HybridEffectsDesc: a size is set).
  Status prepareOutputs() {
    const uint32_t w = desc.width, h = desc.height;
    if (w == 0) return {};
    if (shadow && shadowsSoftByDesc(desc.shadows)) {
      const MemoryOwnerScope scope = own(kOwnShadows);
      if (Status st = ensureDenoiser(shadowDenoiser, true, DenoiseSignal::Scalar, "Denoiser (shadows)"); !st) return st;
    }
    if (ao && !desc.ao.disableDenoiser) {
      const MemoryOwnerScope scope = own(kOwnAo);
      if (Status st = ensureDenoiser(aoDenoiser, true, DenoiseSignal::Scalar, "Denoiser (AO)"); !st) return st;
    }
    if (localLightsDenoised()) {
      const MemoryOwnerScope scope = own(kOwnLocalLights);
      if (Status st = ensureDenoiser(localLightDenoiser, true, DenoiseSignal::Rgb, "Denoiser (local lights)"); !st)
        return st;
    }
    if (reflection && !desc.reflections.disableDenoiser) {
      const MemoryOwnerScope scope = own(kOwnReflections);
      if (Status st = ensureDenoiser(reflectionDenoiser, true, DenoiseSignal::Reflection, "Denoiser (reflections)");
          !st)
        return st;
    }
    if (const uint32_t masks = changeMaskEffects(); masks != 0u) {
      if (Status st = changeMasks.prepare(ctx, masks, w, h); !st) return wrap("change masks", st.error());
    }
    auto prepare = [&](auto* object, Owner owner, const char* what) -> Status {
      if (!object) return {};
      const MemoryOwnerScope scope = own(owner);
      if (Status st = object->prepare(w, h); !st) return wrap(what, st.error());
      return {};
    };
    for (Status st :
         {prepare(shadow.get(), kOwnShadows, "ShadowPass::prepare"), prepare(ao.get(), kOwnAo, "AoPass::prepare"),
          prepare(localLights.get(), kOwnLocalLights, "ManyLightPass::prepare"),
          prepare(reflection.get(), kOwnReflections, "ReflectionPass::prepare"),
          prepare(shadowDenoiser.get(), kOwnShadows, "Denoiser::prepare (shadows)"),
          prepare(aoDenoiser.get(), kOwnAo, "Denoiser::prepare (AO)"),
          prepare(localLightDenoiser.get(), kOwnLocalLights, "Denoiser::prepare (local lights)"),
          prepare(reflectionDenoiser.get(), kOwnReflections, "Denoiser::prepare (reflections)")}) {
      if (!st) return st;
    }
    return {};
  }

  // outputs() from what exists now: each effect's pass image (raw) and its denoiser's where one has run or been
  // prepared, else the neutral image (created here when first needed, retired when nothing names it). Moves
  // `generation` when any image changed.
  Status refreshOutputs() {
    constexpr VkFormat r16 = VK_FORMAT_R16_SFLOAT, rgba16 = VK_FORMAT_R16G16B16A16_SFLOAT;
    constexpr VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    HybridOutputs next;
    // The passes' own images; none (a null view) for an effect that is off or not sized yet.
    if (shadow) {
      const ShadowOutputs& o = shadow->outputs();
      next.shadowRaw = image(o.visibility, o.visibilityView, r16, ro, o.width, o.height);
    }
    if (ao) {
      const AoOutputs& o = ao->outputs();
      next.aoRaw = image(o.ao, o.aoView, r16, ro, o.width, o.height);
    }
    if (reflection) {
      const ReflectionOutputs& o = reflection->outputs();
      next.reflectionRaw = image(o.radiance, o.radianceView, rgba16, ro, o.width, o.height);
    }
    if (localLights) {
      const ManyLightOutputs& o = localLights->outputs();
      next.localLightsRaw = image(o.irradiance, o.irradianceView, rgba16, ro, o.width, o.height);
    }
    if (!next.shadowRaw.view || !next.aoRaw.view || !next.reflectionRaw.view || !next.localLightsRaw.view) {
      if (Status st = neutral.ensure(ctx); !st) return wrap("neutral output images", st.error());
    } else {
      neutral.retire(ctx);  // no byte that nothing reads
    }
    // The image the engine samples: the denoiser's output where it has one, the raw image else, the neutral one
    // (for raw and sampled alike) where the pass has none.
    auto finish = [&](EffectImage& raw, EffectImage& out, const std::unique_ptr<Denoiser>& d, const GpuImage& none) {
      if (!raw.view) {
        raw = out = image(none);
      } else if (d && d->outputs().denoisedView) {
        const DenoiseOutputs& o = d->outputs();
        out = image(o.denoised, o.denoisedView, raw.format, o.layout, o.width, o.height);
      } else {
        out = raw;
      }
    };
    finish(next.shadowRaw, next.shadow, shadowDenoiser, neutral.white());
    finish(next.aoRaw, next.ao, aoDenoiser, neutral.white());
    finish(next.reflectionRaw, next.reflection, reflectionDenoiser, neutral.black());
    finish(next.localLightsRaw, next.localLights, localLightDenoiser, neutral.black());
    next.generation = outputs.generation;
    bool changed = false;
    for (auto member : {&HybridOutputs::shadow, &HybridOutputs::shadowRaw, &HybridOutputs::ao, &HybridOutputs::aoRaw,
                        &HybridOutputs::reflection, &HybridOutputs::reflectionRaw, &HybridOutputs::localLights,
                        &HybridOutputs::localLightsRaw}) {
      changed = changed || !sameImages(next.*member, outputs.*member);
    }
    if (changed) ++next.generation;
    outputs = next;
    return {};
  }

  // Passes follow the effect set; denoisers are decided per frame (hard shadows need none).
  Status applyDesc() {
    const EffectSet e = desc.effects;
    const MemoryOwnerScope scope = own(kOwnShared);
    auto owned = [&](Owner o, auto create) {
      return [this, o, create] {
        const MemoryOwnerScope effectScope = own(o);
        return create();
      };
    };
    Status made = ensure(shadow, e & kEffectShadows, "ShadowPass::create",
                         owned(kOwnShadows, [&] { return ShadowPass::create(ctx); }));
    if (made) made = ensure(ao, e & kEffectAo, "AoPass::create", owned(kOwnAo, [&] { return AoPass::create(ctx); }));
    if (made)
      made = ensure(reflection, e & kEffectReflections, "ReflectionPass::create",
                    owned(kOwnReflections, [&] { return ReflectionPass::create(ctx); }));
    if (made)
      made = ensure(localLights, e & kEffectLocalLights, "ManyLightPass::create",
                    owned(kOwnLocalLights, [&] { return ManyLightPass::create(ctx); }));
    if (made)
      made = ensure(lightList, e & kEffectLocalLights, "LightList::create",
                    owned(kOwnLocalLights, [&] { return LightList::create(ctx); }));
    if (!made) return made;
    if (!shadow || desc.shadows.disableDenoiser) shadowDenoiser.reset();
    if (!ao || desc.ao.disableDenoiser) aoDenoiser.reset();
    if (!localLightsDenoised()) localLightDenoiser.reset();
    if (!reflection || desc.reflections.disableDenoiser) reflectionDenoiser.reset();
    dropScratchWithoutDenoisers();
    if (changeMaskEffects() == 0u) {  // the change masks follow the denoisers (prepareOutputs sizes new ones)
      changeMasks.retire(ctx);
      changes.forget();
    }
    if (Status st = syncMaterialTable(); !st) return st;
    if (Status st = prepareOutputs(); !st) return st;
    return refreshOutputs();
  }

  // No byte that nothing reads: the shared transient images go with the last denoiser.
  void dropScratchWithoutDenoisers() {
    if (desc.disableTransientAliasing || (!shadowDenoiser && !aoDenoiser && !localLightDenoiser && !reflectionDenoiser))
      denoiserScratch.reset();
  }

  // Stochastic local lights are noisy; the exact mode has no noise to remove.
  bool localLightsDenoised() const {
    return localLights && desc.localLights.mode == ManyLightMode::Stochastic && !desc.localLights.disableDenoiser;
  }

  // Records the denoiser of one signal when wanted (ensureDenoiser; refreshOutputs names its output).
  // `rays`: binary rays behind a scalar signal (DenoiseSettings::raysPerPixel; 0 = estimate the noise).
  // `resetFrames`: DenoiseSettings::resetFrames (the pass's reset rays over its rays; 0 = none).
  Status denoise(std::unique_ptr<Denoiser>& slot, bool wanted, const char* what, VkCommandBuffer cmd,
                 const GBufferDesc& gbuffer, VkImageView signal, uint32_t rays,
                 DenoiseSignal kind = DenoiseSignal::Scalar, bool shortHistoryFilter = false,
                 uint32_t resetFrames = 0) {
    if (Status st = ensureDenoiser(slot, wanted, kind, what); !st) return st;
    if (!slot) return {};
    // One at another size (a reflection G-buffer of its own) keeps its own scratch: the shared one is not resized.
    DenoiserScratch* scratch = nullptr;
    if (!desc.disableTransientAliasing && gbuffer.width == frameWidth && gbuffer.height == frameHeight) {
      const MemoryOwnerScope sharedScope = own(kOwnShared);
      if (Status st = ensure(denoiserScratch, true, "DenoiserScratch::create",
                             [&] { return DenoiserScratch::create(ctx); });
          !st)
        return st;
      scratch = denoiserScratch.get();
    }
    DenoiseSettings d = desc.denoiser;
    d.raysPerPixel = kind == DenoiseSignal::Scalar ? rays : 0u;
    d.shortHistoryFilter = d.shortHistoryFilter || shortHistoryFilter;
    d.resetFrames = std::min(resetFrames, d.maxHistoryFrames ? d.maxHistoryFrames : kDefaultMaxHistoryFrames);
    if (Status st = slot->record(cmd, {.gbuffer = gbuffer, .signal = signal, .settings = d, .scratch = scratch}); !st)
      return wrap(what, st.error());
    return {};
  }

  // Each effect's schedule and reset rays as its pass runs them (recordShadows, recordAo), also read by recordChanges:
  // the effects with reset rays get follow-ups.
  RaySchedule shadowSchedule(const ShadowPlan& plan) const {
    RaySchedule wanted = desc.shadows.schedule;
    budget.applyShadows(wanted);
    RaySchedule s = effectSchedule(wanted, shadowDenoiser.get(), plan.soft);
    s.resetRays = plan.soft ? effectResetRays(s, desc.shadows.disableResetRays, plan.rays) : 0u;
    return s;
  }
  uint32_t aoRays() const { return desc.ao.raysPerPixel ? desc.ao.raysPerPixel : kDefaultAoRays; }
  RaySchedule aoSchedule() const {
    RaySchedule wanted = desc.ao.schedule;
    budget.applyAo(wanted);
    RaySchedule s = effectSchedule(wanted, aoDenoiser.get());
    s.resetRays = effectResetRays(s, desc.ao.disableResetRays, aoRays());
    return s;
  }
  ChangeFollowUp changeFollowUp(const HybridFrame& f) const {
    ChangeFollowUp out;
    if (desc.disableResetFollowUp) return out;
    out.frames = desc.resetFollowUpFrames ? desc.resetFollowUpFrames : kDefaultResetFollowUpFrames;
    const ShadowPlan plan = planShadows(desc.shadows, f.light);
    if (shadow && shadowSchedule(plan).resetRays > plan.rays) out.effects |= RB_CHANGE_SHADOWS;
    if (ao && aoSchedule().resetRays > aoRays()) out.effects |= RB_CHANGE_AO;
    return out;
  }

  Status recordShadows(VkCommandBuffer cmd, const HybridFrame& f);
  Status recordAo(VkCommandBuffer cmd, const HybridFrame& f);
  Status recordReflections(VkCommandBuffer cmd, const HybridFrame& f);
  Status recordLocalLights(VkCommandBuffer cmd, const HybridFrame& f);
};

Status HybridEffects::Impl::recordChanges(VkCommandBuffer cmd, const HybridFrame& f, bool trackInstances) {
  const uint32_t effects = changeMaskEffects();
  if (effects == 0u) {
    changeMasks.retire(ctx);  // nothing reads a mask: no byte of it is kept
    changes.forget();         // resumed later, it compares against that frame, not a stale one
    return {};
  }
  const std::span<const Instance> instances = trackInstances ? f.instances : std::span<const Instance>{};
  meshChanges.assign(instances.size(), {});
  if (service && !instances.empty()) service->meshChanges(instances, meshChanges);
  const std::span<const LightSource> lights = localLights ? f.localLights : std::span<const LightSource>{};
  changes.update(instances, meshChanges, lights, f.changedBoxes);
  changes.toGpu(tlas.originOffset, changeFollowUp(f), gpuChangeBoxes);
  ChangeMaskInputs in;
  in.masks = effects;
  // The widest disk a soft shadow samples (planShadows may widen the frame's), so no changed ray is missed.
  in.shadowLight = f.light;
  in.shadowLight.angularRadiusDegrees = std::max(
      {f.light.angularRadiusDegrees, desc.shadows.softAngularRadiusDegrees, kDefaultSoftLightAngularRadiusDegrees});
  in.aoRange = desc.ao.range > 0.0f ? desc.ao.range : kDefaultAoRange;
  Result<bool> recorded = changeMasks.record(ctx, cmd, f.gbuffer, tlas, gpuChangeBoxes, in);
  if (!recorded) return wrap("change masks", recorded.error());
  return {};
}

// The frame's TLAS: the engine's, or the service's pending work and a TLAS over the frame's instances.
Status HybridEffects::Impl::recordTlas(VkCommandBuffer cmd, const HybridFrame& frame) {
  if (frame.tlas && frame.tlas->tlas) {
    tlas = *frame.tlas;
  } else {
    if (!service)
      return invalid(
          "record: the frame brings no TLAS (HybridFrame::tlas) and no AccelerationStructureService was given "
          "to create() to build one over HybridFrame::instances");
    // The acceleration structures are the service's, nobody's in memoryByEffect().
    const MemoryOwnerScope serviceScope(internal::contextImpl(ctx), 0);
    if (auto pending = service->recordPendingWork(cmd); !pending) return wrap("recordPendingWork", pending.error());
    TlasBuildOptions options;
    options.mode = desc.tlasMode;
    if (!desc.worldSpaceTlas) {
      // Camera-relative: precision holds far from the origin (gbuffer.h). The passes read the offset back from
      // TlasInfo, so a G-buffer without cameraPosition (all zero) simply gets a world-space TLAS.
      for (int i = 0; i < 3; ++i) options.originOffset[i] = frame.gbuffer.cameraPosition[i];
    }
    // Vertex data + material per instance: for reflection hits, and for the any-hit alpha tests of non-opaque
    // geometry in every ray; an all-opaque scene without reflections allocates none.
    options.writeShadingRecords = reflection != nullptr || service->nonOpaqueMeshCount() > 0;
    auto built = service->recordTlasBuild(cmd, frame.instances, options);
    if (!built) return wrap("recordTlasBuild", built.error());
    tlas = built.value();
  }
  return {};
}

Status HybridEffects::Impl::recordLocalLights(VkCommandBuffer cmd, const HybridFrame& f) {
  const MemoryOwnerScope scope = own(kOwnLocalLights);
  ManyLightSettings s;
  s.mode = desc.localLights.mode;
  s.raysPerPixel = budget.localLightRays(desc.localLights.raysPerPixel ? desc.localLights.raysPerPixel
                                                                       : kDefaultLightRays);
  s.candidates = desc.localLights.candidates;
  s.materials = materials.get();
  s.schedule = effectSchedule(desc.localLights.schedule, localLightDenoiser.get());
  if (Status st = lightList->record(cmd, tlas, f.localLights); !st) return wrap("HybridFrame::localLights", st.error());
  const GBufferDesc g = changeMasks.gbufferFor(f.gbuffer, RB_CHANGE_LOCAL_LIGHTS);
  if (Status st = localLights->record(cmd, {.gbuffer = g, .tlas = tlas, .lightList = lightList.get(), .settings = s});
      !st)
    return wrap("ManyLightPass::record", st.error());
  const ManyLightOutputs& o = localLights->outputs();
  return denoise(localLightDenoiser, localLightsDenoised(), "Denoiser (local lights)", cmd, g, o.irradianceView, 0,
                 DenoiseSignal::Rgb);
}

Status HybridEffects::Impl::recordShadows(VkCommandBuffer cmd, const HybridFrame& f) {
  const MemoryOwnerScope scope = own(kOwnShadows);
  const ShadowPlan plan = planShadows(desc.shadows, f.light);
  ShadowSettings s;
  s.raysPerPixel = plan.rays;
  s.materials = materials.get();  // alpha tests non-opaque geometry
  // Adaptive rays and converged tiles: only for soft shadows, whose denoiser runs after the pass this frame.
  s.schedule = shadowSchedule(plan);
  const GBufferDesc g = changeMasks.gbufferFor(f.gbuffer, RB_CHANGE_SHADOWS);
  if (Status st = shadow->record(cmd, {.gbuffer = g, .tlas = tlas, .light = plan.light, .settings = s}); !st)
    return wrap("ShadowPass::record", st.error());
  const ShadowOutputs& o = shadow->outputs();
  // The visibility is a fraction of plan.rays binary rays; with adaptive rays the count varies per pixel, so the
  // denoiser measures the noise instead.
  return denoise(shadowDenoiser, plan.soft && !desc.shadows.disableDenoiser, "Denoiser (shadows)", cmd, g,
                 o.visibilityView, s.schedule.adaptive.enabled ? 0u : plan.rays, DenoiseSignal::Scalar, false,
                 denoiserResetFrames(s.schedule.resetRays, plan.rays));
}

Status HybridEffects::Impl::recordAo(VkCommandBuffer cmd, const HybridFrame& f) {
  const MemoryOwnerScope scope = own(kOwnAo);
  AoSettings s;
  s.materials = materials.get();
  s.raysPerPixel = desc.ao.raysPerPixel;
  s.range = desc.ao.range;
  s.estimator = desc.ao.estimator;
  s.schedule = aoSchedule();
  const GBufferDesc g = changeMasks.gbufferFor(f.gbuffer, RB_CHANGE_AO);
  if (Status st = ao->record(cmd, {.gbuffer = g, .tlas = tlas, .settings = s}); !st)
    return wrap("AoPass::record", st.error());
  const AoOutputs& o = ao->outputs();
  // Binary AO is a fraction of binary rays; distance-weighted AO is not, nor is adaptive AO (the count varies per
  // pixel), so their noise is estimated.
  const uint32_t rays = s.estimator == AoEstimator::Binary && !s.schedule.adaptive.enabled ? aoRays() : 0u;
  return denoise(aoDenoiser, !desc.ao.disableDenoiser, "Denoiser (AO)", cmd, g, o.aoView, rays, DenoiseSignal::Scalar,
                 !desc.ao.disableShortHistoryFilter, denoiserResetFrames(s.schedule.resetRays, aoRays()));
}

Status HybridEffects::Impl::recordReflections(VkCommandBuffer cmd, const HybridFrame& f) {
  const MemoryOwnerScope scope = own(kOwnReflections);
  ReflectionSettings s{.roughnessThreshold = desc.reflections.roughnessThreshold, .materials = materials.get()};
  s.raysPerPixel = desc.reflections.raysPerPixel;
  s.invocationReorder = desc.reflections.invocationReorder;
  RaySchedule wanted = desc.reflections.schedule;
  budget.applyReflections(wanted, s.raysPerPixel);
  s.schedule = effectSchedule(wanted, reflectionDenoiser.get());
  s.lighting = reflectionLighting(f);
  // The light changes a reflection shows, where the change resets run (the denoiser then drops those pixels'
  // history; effect_schedule.h says why lights only).
  if (reflectionDenoiser && !desc.reflections.disableRelitResets &&
      (changeMaskEffects() & RB_CHANGE_REFLECTIONS) != 0u) {
    reflectionRelitBoxes(changes.boxes(), reflectionRelit);
    s.relitBoxes = reflectionRelit;
  }
  if (lightList && !f.localLights.empty()) s.lights = lightList.get();  // recorded earlier this frame
  const GBufferDesc& source = f.reflectionGBuffer ? *f.reflectionGBuffer : f.gbuffer;
  const GBufferDesc g = changeMasks.gbufferFor(source, RB_CHANGE_REFLECTIONS);
  ReflectionFrame in{.gbuffer = g, .tlas = tlas, .settings = s};
  // This frame's sun visibility of the same pixels (one depth buffer; denoised where soft): rough lobes' hits read it.
  if (shadow && !desc.reflections.disableSunFromScreen && source.depth.view == f.gbuffer.depth.view &&
      f.light.type == LightType::Directional)
    in.sunVisibility.view = shadowDenoiser ? shadowDenoiser->outputs().denoisedView : shadow->outputs().visibilityView;
  if (Status st = reflection->record(cmd, in); !st) return wrap("ReflectionPass::record", st.error());
  // Guided by the roughness of the G-buffer the rays were traced from.
  return denoise(reflectionDenoiser, !desc.reflections.disableDenoiser, "Denoiser (reflections)", cmd, g,
                 reflection->outputs().radianceView, 0, DenoiseSignal::Reflection);
}

Result<std::unique_ptr<HybridEffects>> HybridEffects::create(Context& context, AccelerationStructureService* service,
                                                             const HybridEffectsDesc& desc) {
  if (Status s = validateHybridEffectsDesc(desc); !s) return s.error();
  std::unique_ptr<HybridEffects> fx(new HybridEffects(std::make_unique<Impl>(context, service)));
  if (Status s = fx->impl_->budget.configure(context, desc); !s) return s.error();
  fx->impl_->desc = desc;
  if (Status s = fx->impl_->applyDesc(); !s) return s.error();
  return fx;
}

HybridEffects::HybridEffects(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HybridEffects::~HybridEffects() = default;  // the passes retire their objects to the Context

Status HybridEffects::setDesc(const HybridEffectsDesc& desc) {
  if (Status s = validateHybridEffectsDesc(desc); !s) return s;
  if (Status s = impl_->budget.configure(impl_->ctx, desc); !s) return s;
  impl_->desc = desc;
  return impl_->applyDesc();
}

Status HybridEffects::resize(uint32_t width, uint32_t height) {
  if (width == 0 || height == 0) {
    return invalid(
        "resize " + std::to_string(width) + "x" + std::to_string(height) +
        " is empty: pass the G-buffer's size (setDesc with width = height = 0 follows the G-buffer instead)");
  }
  HybridEffectsDesc d = impl_->desc;
  d.width = width;
  d.height = height;
  return setDesc(d);
}

const HybridEffectsDesc& HybridEffects::desc() const { return impl_->desc; }

Status HybridEffects::setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures) {
  Impl& a = *impl_;
  const MemoryOwnerScope scope = a.own(Impl::kOwnShared);
  if (a.materials) {
    if (Status st = a.materials->setMaterials(materials, textures); !st)
      return wrap("MaterialTable::setMaterials", st.error());
  }
  a.materialData.assign(materials.begin(), materials.end());
  a.textureData.assign(textures.begin(), textures.end());
  a.haveMaterialData = true;
  return {};
}

Status HybridEffects::record(VkCommandBuffer cmd, const HybridFrame& frame) {
  Impl& a = *impl_;
  if (!cmd) return invalid("record: cmd is VK_NULL_HANDLE");
  const MemoryOwnerScope scope = a.own(Impl::kOwnShared);
  if (a.desc.effects == 0) {
    a.neutral.recordInit(a.ctx, cmd);
    return {};  // nothing enabled: no TLAS, no rays
  }
  const GBufferDesc& g = frame.gbuffer;
  if (Status st = validateHybridFrame(a.desc, frame, a.shadow || a.reflection); !st) return st;
  // Sun, sky and ambient of reflection hits: by the one resolver the pass uses, before anything is recorded.
  if (a.reflection) {
    Result<ResolvedLighting> lit = resolveSceneLighting(reflectionLighting(frame),
                                                        "HybridEffects: record: HybridFrame::lighting");
    if (!lit) return lit.error();
  }
  a.neutral.recordInit(a.ctx, cmd);
  if (Status st = a.budget.begin(a.ctx, cmd); !st) return wrap("frame budget", st.error());
  if (a.budget.active()) a.budget.plan(a.ctx, stats());  // the passes' stats only where a budget reads them
  a.frameWidth = g.width;
  a.frameHeight = g.height;
  // Every failure from here on still records the hook's end timestamp below: a start without an end would leave
  // the frame's timing unfinished.
  Status st = a.recordTlas(cmd, frame);
  if (st) st = a.recordChanges(cmd, frame, !(frame.tlas && frame.tlas->tlas));
  if (st && a.shadow) st = a.recordShadows(cmd, frame);
  if (st && a.ao) st = a.recordAo(cmd, frame);
  if (st && a.localLights) st = a.recordLocalLights(cmd, frame);
  if (st && a.reflection) st = a.recordReflections(cmd, frame);
  a.dropScratchWithoutDenoisers();  // hard shadows drop theirs frame by frame
  // A first frame of a size-following description, or the shadow effect between soft and hard, may have changed
  // the images; an error leaves the existing ones named.
  Status refreshed = a.refreshOutputs();
  a.neutral.recordInit(a.ctx, cmd);
  a.budget.end(a.ctx, cmd);
  if (!st) return st;
  return refreshed;
}

const HybridOutputs& HybridEffects::outputs() const { return impl_->outputs; }
const TlasInfo& HybridEffects::lastTlas() const { return impl_->tlas; }

EffectImage HybridEffects::changeMask(EffectSet effect) const {
  uint32_t bit = 0;
  if (effect == kEffectShadows) bit = RB_CHANGE_SHADOWS;
  if (effect == kEffectAo) bit = RB_CHANGE_AO;
  if (effect == kEffectLocalLights) bit = RB_CHANGE_LOCAL_LIGHTS;
  if (effect == kEffectReflections) bit = RB_CHANGE_REFLECTIONS;
  const GpuImage* image = impl_->changeMasks.mask(bit);
  if (!image) return {};
  return {image->image, image->view,  image->format, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
          image->width, image->height};
}

void HybridEffects::resetHistory() {
  impl_->changes.forget();
  impl_->changeMasks.clear();
  if (impl_->shadowDenoiser) impl_->shadowDenoiser->resetHistory();
  if (impl_->aoDenoiser) impl_->aoDenoiser->resetHistory();
  if (impl_->localLightDenoiser) impl_->localLightDenoiser->resetHistory();
  if (impl_->reflectionDenoiser) impl_->reflectionDenoiser->resetHistory();
}

HybridStats HybridEffects::stats() const {
  Impl& a = *impl_;
  return {statsOf(a.shadow),
          statsOf(a.shadowDenoiser),
          statsOf(a.ao),
          statsOf(a.aoDenoiser),
          statsOf(a.reflection),
          statsOf(a.localLights),
          statsOf(a.localLightDenoiser),
          statsOf(a.reflectionDenoiser),
          a.changeMasks.stats(a.ctx),
          a.budget.hook(a.ctx),
          a.budget.stats()};
}

MemoryStats HybridEffects::memoryStats() const {
  MemoryStats all = impl_->ctx.memoryStats();
  MemoryStats passes;
  for (MemoryCategory c : {MemoryCategory::ShaderTables, MemoryCategory::PassImages, MemoryCategory::PassBuffers})
    passes.bytes[size_t(c)] = all.of(c);
  passes.allocations = all.allocations;
  return passes;
}

EffectMemoryStats HybridEffects::memoryByEffect() const {
  const Context::Impl& c = internal::contextImpl(impl_->ctx);
  auto of = [&](Impl::Owner o) { return c.ownerMemory[impl_->owners[o] - 1]; };
  return {of(Impl::kOwnShadows), of(Impl::kOwnAo), of(Impl::kOwnReflections), of(Impl::kOwnLocalLights),
          of(Impl::kOwnShared)};
}

const ShadowPass* HybridEffects::shadowPass() const { return impl_->shadow.get(); }
const AoPass* HybridEffects::aoPass() const { return impl_->ao.get(); }
const ReflectionPass* HybridEffects::reflectionPass() const { return impl_->reflection.get(); }
const ManyLightPass* HybridEffects::localLightPass() const { return impl_->localLights.get(); }
const Denoiser* HybridEffects::shadowDenoiser() const { return impl_->shadowDenoiser.get(); }
const Denoiser* HybridEffects::aoDenoiser() const { return impl_->aoDenoiser.get(); }
const Denoiser* HybridEffects::localLightDenoiser() const { return impl_->localLightDenoiser.get(); }
const Denoiser* HybridEffects::reflectionDenoiser() const { return impl_->reflectionDenoiser.get(); }

}  // namespace rb
