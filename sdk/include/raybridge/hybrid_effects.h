// The effects front end: one object that turns an effect set (or a preset) into passes and denoisers, records
// them in order into the engine's command buffer each frame and hands back the images the engine's lighting
// samples. Engines that want the passes one by one still use ShadowPass, AoPass, ReflectionPass and Denoiser
// directly; this object only composes them.
//
//   rb::HybridEffectsDesc desc{.effects = rb::kEffectShadows | rb::kEffectAo, .width = w, .height = h};
//   auto fx = rb::HybridEffects::create(context, &service, desc);
//   if (!fx) return fail(fx.what());                    // the message names the field and the fix
//   writeDescriptors(fx.value()->outputs());            // once: the views stay valid (see Outputs below)
//   fx.value()->setMaterials(materials, textureViews);  // once per scene: reflection hits and alpha tests
//   // each frame, after ctx.beginFrame() and the G-buffer pass:
//   rb::HybridFrame frame;
//   frame.gbuffer = gbuffer;                            // the engine's pre-pass (gbuffer.h)
//   frame.instances = instances;                        // or frame.tlas = the engine's own TLAS
//   frame.light = sun;                                  // the light the shadow effect shadows
//   frame.localLights = lights;                         // the engine's light list (local lights effect)
//   if (rb::Status st = fx->record(cmd, frame); !st) log(st.what());  // BLAS work, TLAS, effects, denoising
//   // the engine's lighting samples outputs().shadow.view ... (SHADER_READ_ONLY_OPTIMAL, no barrier needed)
//
// Outputs: with HybridEffectsDesc::width/height set, create() and resize() allocate every output, so outputs()
// names its images before the first record() and its views stay valid, frame after frame, until the next resize(),
// setDesc() or applyPreset() that changes them; HybridOutputs::generation counts those changes (compare it each
// frame and rewrite descriptors only when it moved). An effect that is off names a 1x1 neutral image: white
// (1.0) for shadow and AO, zero for reflection and local lights; sample outputs with normalized coordinates
// (texture(), any address mode but CLAMP_TO_BORDER) and a disabled effect reads as "no effect". Every image is
// written (neutral ones cleared) by the first record(): sample none before it. One output changes by itself: the
// shadow effect's switches between denoised and raw when the frame's light switches between soft and hard
// (ShadowEffectSettings), and generation says so.
//
// Order inside record(): pending BLAS work and the TLAS (when it builds one) -> change masks (on a frame with a known
// change, see below) -> shadows [-> denoiser] -> AO [-> denoiser] -> local lights [-> denoiser] -> reflections
// [-> denoiser]. Only what the description enables exists: a disabled effect has no pass, no denoiser, no image of its
// own and traces no ray; hard shadows (one ray) are never denoised. The G-buffer hand-over (stages, accesses, layouts)
// is in gbuffer.h.
//
// Change resets: the denoisers restart where the SDK knows the world changed, not only where their anti-lag sees it
// (denoiser.h). Each frame compares HybridFrame::instances (when record() builds the TLAS) and localLights with the
// previous frame's, entry by entry (keep their order from frame to frame). An instance whose transform or mesh
// changed, that appeared or vanished, or whose dynamic mesh brought a new pose box (MeshUpdate::bounds; an update
// without one counts as a change) changes its old and new world box: the mesh's box (MeshDesc::bounds, or the pose
// box) under the transform; a mesh without a known box is left to anti-lag. A local light that changed changes its
// old and new range. HybridFrame::changedBoxes adds the engine's own. A compute pass turns them into one mask per
// denoised effect (1 byte a pixel each, allocated with the denoisers):
//   - every effect: pixels whose surface lies in a box (the object itself);
//   - shadows: pixels whose ray to HybridFrame::light crosses a box (the old and new shadow);
//   - AO: pixels within AoEffectSettings::range of a box (the contact shadow it left and brought);
//   - local lights: pixels within a changed light's range (a light of unlimited range changes every pixel).
// The effect's denoiser, converged tiles and adaptive rays read its mask as they read the engine's reactive mask
// (which the masks include): those pixels start afresh, every other pixel keeps its history. A frame without a known
// change records nothing for it. The shadow light itself (HybridFrame::light) is not tracked: a sun that turns slowly
// would reset every pixel each frame; anti-lag follows it. changeMask() shows a mask.
//
// Lifetime: setDesc()/applyPreset() and the destructor retire passes to the Context's deferred release (see
// context.h), so switching effects mid-run needs no wait-idle. Destroy it before its Context and before the
// AccelerationStructureService it was given.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/ao_pass.h>
#include <raybridge/denoiser.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>
#include <raybridge/many_light_pass.h>
#include <raybridge/presets.h>
#include <raybridge/reflection_pass.h>
#include <raybridge/scene_lighting.h>
#include <raybridge/shadow_pass.h>

#include <memory>
#include <span>

namespace rb {

// Defaults of the settings below (what a zero field means): kDefaultSoftShadowRays (shadow_pass.h),
// kDefaultAoRays and kDefaultAoRange (ao_pass.h), kDefaultReflectionRoughnessThreshold, kDefaultReflectionRays,
// kDefaultSunRadiance, kDefaultSkyRadiance and kDefaultAmbientIntensity (reflection_pass.h), and:
// Angular radius given to a directional light without one when more than one shadow ray is asked for: the
// sun's apparent size (0.27 degrees) widened a little, as games do to read as a soft sun.
inline constexpr float kDefaultSoftLightAngularRadiusDegrees = 0.5f;
// Largest HybridEffectsDesc::width and height (Vulkan's guaranteed maxImageDimension2D is 4096; every ray tracing
// device seen allows 16384 or more).
inline constexpr uint32_t kMaxHybridOutputSize = 16384;

// RaySchedule::resetRays that HybridEffects asks for when the effect's schedule leaves it 0: this many times the
// effect's rays per pixel in the pixels whose history a change restarts (the effect's change mask, the engine's
// reactive mask), for denoised soft shadows and AO without adaptive rays or half resolution. Four: measured on
// tests/motion_lag_test.cpp's teleport (docs/effects.md, "Reset rays"). ShadowEffectSettings::disableResetRays and
// AoEffectSettings::disableResetRays turn it off.
inline constexpr uint32_t kDefaultResetRaysFactor = 4;
// HybridEffectsDesc::resetFollowUpFrames when left 0: after a change restarts a pixel's history, the effects with reset
// rays trace them there for this many more frames (the change's boxes are sent again as follow-up boxes), and the
// denoiser adds each such frame as resetRays / raysPerPixel frames. One frame of reset rays is still several times
// the error of a long history where the signal is wide and soft (a penumbra at 2560x1440: docs/effects.md, "Reset
// rays"); the follow-ups close that gap over the first frames without restarting anything. Three: measured on the
// motion bench's teleport.
inline constexpr uint32_t kDefaultResetFollowUpFrames = 3;
// Largest HybridEffectsDesc::resetFollowUpFrames (the change tracker keeps this many frames of boxes).
inline constexpr uint32_t kMaxResetFollowUpFrames = 8;

// ---- Frame budget (HybridEffectsDesc::budgetMs) ----
//
// record() times itself (HybridStats::hook) and each pass; from finished frames the front end estimates the fixed cost
// (the TLAS, the change masks, the denoisers, hard shadows) and divides what is left of the budget:
//  - denoised soft shadows and denoised AO trace adaptive rays under a time target each (ray_schedule.h): what is
//    left goes to them in proportion to the error a millisecond buys each (kBudgetShadowErrorWeight,
//    kBudgetAoErrorWeight), an effect whose rays reach their maximum leaving the rest to the other. Their
//    schedule.adaptive settings are taken as given but for enabled, timeBudgetMs and initialRaysPerPixel, which the
//    budget sets (their reset rays give way to the plan);
//  - reflections step from as described (level 0) through their glossy rays halved down to one, then (unless they are
//    at half resolution already) one ray at half resolution, without converged tiles; stochastic local lights from
//    their rays per pixel down to one (level k = raysPerPixel / 2^k): a step at a time, a step up only where the
//    measured (or predicted) cost leaves the adaptive effects twice the share they need.
// Every effect starts at its cheapest and climbs as the measurements show room: the budget holds from the first
// frames. The division is src/schedule/frame_budget.h's, tested with injected timings. A budget under the floor
// (fixed cost plus every effect at its cheapest) runs everything at its cheapest: HybridStats::budget reports
// belowFloor and floorMs. Held on the H100 at 2560x1440 (docs/performance.md, "Frame budget").
inline constexpr float kMaxFrameBudgetMs = 1000.0f;
// The error weights of the split: a Monte Carlo error falls as a / sqrt(ms), and the split that minimises the summed
// squared error gives each effect time in proportion to a. Measured by raybridge-effects-bench --scenario adaptive
// (docs/performance.md, "Adaptive rays": per-tile adaptive rays at equal time, H200, 2560x1440): soft shadows RMSE
// 0.00630 at 1.42 ms, AO 0.01456 at 1.33 ms; a = RMSE x sqrt(ms).
inline constexpr double kBudgetShadowErrorWeight = 0.0075;
inline constexpr double kBudgetAoErrorWeight = 0.0168;

struct ShadowEffectSettings {
  // 0 = the light decides: kDefaultSoftShadowRays for a light with a size, one ray (hard) for one without.
  // 1 = hard shadows whatever the light's size (the presets' "1 ray"), unless softAngularRadiusDegrees is set:
  //     then one stochastic ray over that disk per pixel.
  // N > 1 = N rays over the light's disk; a directional light without a size gets softAngularRadiusDegrees, or
  //     kDefaultSoftLightAngularRadiusDegrees; a point or spot light without a radius stays hard.
  uint32_t raysPerPixel = 0;
  // Directional lights: the angular radius to use instead of the light's own. 0 = the light's own.
  float softAngularRadiusDegrees = 0.0f;
  bool disableDenoiser = false;  // false = soft shadows are denoised (hard shadows never are)
  // Where and how many rays (ray_schedule.h; ShadowSettings::schedule): the tile classifier, and for soft shadows
  // adaptive rays (raysPerPixel is then the average the budget is made of) and converged tiles (the raw shadow
  // output then holds kept-history marks there, the denoised one is complete). Adaptive rays and converged tiles
  // need the effect's denoiser (disableDenoiser = false); schedule.history is set to it (a value given is ignored).
  // schedule.resetRays 0 = kDefaultResetRaysFactor x raysPerPixel for denoised soft shadows without adaptive rays.
  RaySchedule schedule{};
  // false = more rays where a change restarts a soft shadow's history (schedule.resetRays, or the default above).
  // true = every pixel traces raysPerPixel.
  bool disableResetRays = false;
};

struct AoEffectSettings {
  uint32_t raysPerPixel = 0;  // 0 = kDefaultAoRays
  float range = 0.0f;         // 0 = kDefaultAoRange
  AoEstimator estimator = AoEstimator::Binary;
  bool disableDenoiser = false;  // false = denoised
  // false = the AO denoiser filters pixels with a short history harder (DenoiseSettings::shortHistoryFilter; binary
  // AO without adaptive rays, whose rays per pixel are known). true = as every other pixel, unless
  // HybridEffectsDesc::denoiser.shortHistoryFilter asks for it on every scalar signal.
  bool disableShortHistoryFilter = false;
  // Where and how many rays (ray_schedule.h; AoSettings::schedule): adaptive rays, half resolution (a quarter of
  // the rays, depth-aware upsample; every preset with AO sets it) and converged tiles (full resolution; the raw AO
  // output then holds kept-history marks there, the denoised one is complete). Adaptive rays and converged tiles
  // need the effect's denoiser; schedule.history is set to it (a value given is ignored). schedule.resetRays 0 =
  // kDefaultResetRaysFactor x raysPerPixel for denoised AO without adaptive rays or half resolution.
  RaySchedule schedule{};
  // false = more rays where a change restarts the AO's history (schedule.resetRays, or the default above). true =
  // every pixel traces raysPerPixel.
  bool disableResetRays = false;
};

struct ReflectionEffectSettings {
  float roughnessThreshold = 0.0f;  // 0 = kDefaultReflectionRoughnessThreshold: rougher pixels trace nothing
  uint32_t raysPerPixel = 0;        // glossy pixels; 0 = kDefaultReflectionRays (mirrors trace one)
  // false = denoised (a DenoiseSignal::Reflection Denoiser, HybridEffectsDesc::denoiser's settings): glossy
  // pixels are filtered as far as their noise asks, mirrors (roughness 0) are not blurred.
  bool disableDenoiser = false;
  // false (default) = never reorder; true = shader execution reordering where the Context has it
  // (ReflectionSettings's field of the same name). reflectionPass()->reordered() says whether the latest frame
  // reordered.
  bool invocationReorder = false;
  // Where and how many rays (ray_schedule.h; ReflectionSettings::schedule): half resolution, and converged tiles
  // (full resolution; skip the tiles whose denoised history has converged and whose view has not turned: the raw
  // output then holds kept-history marks there, a = -1, the denoised one is complete; needs the effect's
  // denoiser). schedule.history is set to the effect's denoiser (a value given is ignored).
  RaySchedule schedule{};
  // Light resets (on by default): the reflection rays test the reach of every local light that changed this frame
  // (ReflectionSettings::relitBoxes) and the denoiser restarts the pixels whose reflection hit lies in one: a lamp that
  // moved or switched, seen in a mirror, which anti-lag alone follows over many frames. With change resets on and the
  // denoiser, at full resolution; moved objects are left to anti-lag (src/frontend/effect_schedule.h says why). On the
  // motion bench's lamp jump at 2560x1440 (H100, 2026-12-06, docs/effects.md "Motion") the reflections' lag went from
  // more than 6 frames to 2 at 1, 4 and 16 rays and their mean error down by a fifth; their flicker rose to 0.5-0.7x
  // the reference's (0.2x without). true = reflections follow every change by anti-lag alone.
  bool disableRelitResets = false;
  // false (default) = hits of rough lobes read their sun visibility from this frame's shadow effect where they are
  // the surface on screen (ReflectionFrame::sunVisibility; reflection_pass.h, "Sun visibility from the screen"),
  // when the shadow effect is on for the directional sun and the reflection G-buffer has the frame's depth buffer.
  // true = every hit traces its sun shadow ray.
  bool disableSunFromScreen = false;
};

struct LocalLightEffectSettings {
  ManyLightMode mode = ManyLightMode::Stochastic;  // Exact = one ray per light per pixel (few lights, references)
  uint32_t raysPerPixel = 0;                       // Stochastic: 0 = kDefaultLightRays
  uint32_t candidates = 0;                         // Stochastic: 0 = kDefaultLightCandidates
  // false = Stochastic output is denoised (an RGB Denoiser, HybridEffectsDesc::denoiser's settings); Exact is
  // never denoised: it has no noise.
  bool disableDenoiser = false;
  // Where and how many rays (ray_schedule.h; ManyLightSettings::schedule): converged tiles, Stochastic only (skip
  // the tiles whose denoised irradiance has converged: the raw output then holds kept-history marks there, a = -1,
  // the denoised one is complete; needs the effect's denoiser). schedule.history is set to the effect's denoiser.
  RaySchedule schedule{};
};

// What runs. A zero-initialised description is valid: no effect, nothing traced, nothing allocated but the two 1x1
// neutral images the outputs name (see Outputs).
struct HybridEffectsDesc {
  EffectSet effects = 0;
  // Size of the outputs, the G-buffer's. Set: create()/setDesc()/resize() allocate the outputs at this size and
  // record() requires a G-buffer of it (an error names both sizes otherwise). 0 = follow the G-buffer: the outputs
  // are allocated by the first record() and re-allocated when its size changes (generation reports it).
  uint32_t width = 0;
  uint32_t height = 0;
  ShadowEffectSettings shadows{};
  AoEffectSettings ao{};
  ReflectionEffectSettings reflections{};
  LocalLightEffectSettings localLights{};
  // Shared by the shadow, AO, local light and reflection denoisers (raysPerPixel is filled in per scalar signal).
  DenoiseSettings denoiser{};
  // Build the TLAS with camera-relative origin (TlasBuildOptions::originOffset = the G-buffer's camera
  // position), so precision holds far from the world origin. Only used when record() builds the TLAS.
  bool worldSpaceTlas = false;  // false = camera-relative (recommended)
  // How record() builds the TLAS each frame (TlasBuildOptions::mode). Default Adaptive: refits, and rebuilds
  // when the instances drifted apart or every kDefaultTlasMaxRefits frames. Only used when record() builds the TLAS.
  TlasBuildMode tlasMode = TlasBuildMode::Adaptive;
  // false = change resets (see "Change resets" above). true = the denoisers follow changes by anti-lag alone.
  bool disableChangeResets = false;
  // Frames after a change that its pixels still trace the reset rays, in the effects that have them (follow-ups;
  // with change resets only). 0 = kDefaultResetFollowUpFrames; at most kMaxResetFollowUpFrames. Follow-up boxes take
  // the room of the GPU's per-frame box list (256) that the frame's own changes leave; beyond it they are dropped
  // (fewer extra rays, no missed restart). The pixels seen through where a moved, deformed or vanished instance was (or
  // through an engine box) are follow-up pixels too, on the change's frame and its follow-ups: they may be newly
  // visible, with no history to reproject, and would otherwise start from one frame of the usual rays (the motion
  // bench's teleport: half the shadows' changed pixels; docs/effects.md, "Revealed pixels").
  uint32_t resetFollowUpFrames = 0;
  // true = no follow-ups: only the frame of a change traces the reset rays, and only where it restarts a history.
  bool disableResetFollowUp = false;
  // The frame budget: GPU milliseconds for the whole record() (the TLAS, the change masks, every pass and denoiser),
  // which the front end holds by dividing what the fixed costs leave between the effects, from its own timestamps of
  // finished frames ("Frame budget" above). 0 = off: every effect runs as described. At most kMaxFrameBudgetMs; needs
  // GPU timestamps on the Context's queue family (create()/setDesc() name the problem otherwise).
  float budgetMs = 0.0f;
  // false = the denoisers share one set of transient images (DenoiserScratch: written and read within one denoiser's
  // record, so denoisers recorded one after another alias them; "Memory by effect" in docs/integration.md). true =
  // each denoiser keeps its own: 20 B/px more in `high`, the same images bit for bit
  // (tools/tests/preset_hash_test.cpp checks every preset both ways). For ruling aliasing out when an image looks
  // wrong, and for tools that record one denoiser's work elsewhere.
  bool disableTransientAliasing = false;
};

// `base` with the preset's effect set, ray counts, AO resolution and whether soft shadows skip converged tiles
// (every other field is kept).
HybridEffectsDesc withPreset(HybridEffectsDesc base, Preset preset);

// Largest HybridFrame::changedBoxes. Boxes beyond the GPU's per-frame list (256, with the SDK's own) are merged.
inline constexpr uint32_t kMaxEngineChangedBoxes = 4096;

// One frame's inputs. gbuffer is required; the scene comes from `tlas` or `instances`.
struct HybridFrame {
  GBufferDesc gbuffer{};
  // Optional G-buffer with the shading normal and roughness for reflections, when `gbuffer` uses another
  // normal (e.g. geometric normals for conformance checks). nullptr = gbuffer.
  const GBufferDesc* reflectionGBuffer = nullptr;
  // The engine's TLAS (tlas->tlas != VK_NULL_HANDLE): used as is; with reflections it must carry shading
  // records. nullptr = record() records the service's pending work and builds a TLAS over `instances`.
  const TlasInfo* tlas = nullptr;
  std::span<const Instance> instances{};
  Light light{};  // the light the shadow effect shadows and reflection hits are lit by (default: the sun, up)
  // The engine's light list for the local lights effect (light_list.h; at most kMaxLights), this frame's
  // positions, also lighting reflection hits. Copied during record(). Empty = black, no rays.
  std::span<const LightSource> localLights{};
  // Lighting of reflection hits (scene_lighting.h): sunRadiance is `light`'s radiance (colour * intensity),
  // skyRadiance what escaping rays return, ambientIntensity the sky light on hit surfaces; zeros mean the defaults
  // unless explicitValues. The sun's direction is `light`'s: lighting.sunDirection and lighting.noSun are not read
  // (a point or spot `light` leaves the hits to the sky).
  SceneLighting lighting{};
  // Where the engine knows the world changed (a teleport, a cut-scene swap, geometry the SDK does not see): reset
  // like a moved instance's box (see "Change resets"). At most kMaxEngineChangedBoxes. Copied during record().
  std::span<const ChangedBox> changedBoxes{};
};

// An image the front end owns: left in `layout` after record(), readable by fragment, compute and ray tracing
// shaders with no barrier of the engine's.
struct EffectImage {
  VkImage image = VK_NULL_HANDLE;  // never VK_NULL_HANDLE once create() succeeded (a 1x1 neutral image when off)
  VkImageView view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
};

// The images the engine's lighting samples (see Outputs above). `shadow`, `ao`, `reflection` and `localLights` are
// denoised where a denoiser runs, else raw; the raw images stay available. An effect that is off names the neutral
// image. After a record() that failed, the images hold an earlier frame (or, before any record, nothing): keep the
// engine's own lighting terms for that frame.
struct HybridOutputs {
  // Changes whenever any image or view below changes (resize, an effect switched, the shadow effect between soft
  // and hard); equal generations name the same images.
  uint64_t generation = 0;
  EffectImage shadow, shadowRaw;  // R16_SFLOAT visibility, 1 = lit
  EffectImage ao, aoRaw;          // R16_SFLOAT open fraction, 1 = open
  // R16G16B16A16_SFLOAT radiance, a = 1 where rays were traced: reflection is denoised unless
  // ReflectionEffectSettings::disableDenoiser, else it is reflectionRaw.
  EffectImage reflection, reflectionRaw;
  // R16G16B16A16_SFLOAT shadowed diffuse irradiance of the local lights (ManyLightOutputs): localLights is
  // denoised in Stochastic mode unless LocalLightEffectSettings::disableDenoiser; else it is localLightsRaw.
  EffectImage localLights, localLightsRaw;
};

// HybridEffects' device memory by effect (HybridEffects::memoryByEffect), in the Context's pass categories
// (ShaderTables, PassImages, PassBuffers; the others are 0): each effect's pass, its denoiser and its ray schedule's
// images and buffers (local lights: their light list too). `shared`: what serves several effects (the change masks,
// the material table, the neutral images named for effects that are off, the denoisers' one DenoiserScratch). The total
// equals memoryStats() when no other HybridEffects or engine-made pass shares the Context. `allocations`: the live
// allocations of each.
struct EffectMemoryStats {
  MemoryStats shadows, ao, reflections, localLights, shared;
  MemoryStats total() const {
    MemoryStats sum;
    for (const MemoryStats* m : {&shadows, &ao, &reflections, &localLights, &shared}) {
      for (size_t c = 0; c < static_cast<size_t>(MemoryCategory::Count); ++c) sum.bytes[c] += m->bytes[c];
      sum.allocations += m->allocations;
    }
    return sum;
  }
};

// The frame budget as the latest record() planned it (HybridEffectsDesc::budgetMs; all zero when off).
struct FrameBudgetStats {
  float budgetMs = 0.0f;
  double fixedMs = 0.0;  // estimated: what no effect's setting moves (the TLAS, change masks, denoisers, hard shadows)
  double floorMs = 0.0;  // estimated least frame: the fixed cost and every effect at its cheapest
  bool belowFloor = false;  // budgetMs < floorMs: every effect runs at its cheapest and the frame takes floorMs
  // Per effect: the time it was given (an adaptive effect's time target; a levelled one's measured cost at its level).
  double shadowsMs = 0.0, aoMs = 0.0, reflectionsMs = 0.0, localLightsMs = 0.0;
  // 0 = as described; level k < log2(rays) + 1: the glossy rays / 2^k; the next (the last): one ray, half resolution.
  uint32_t reflectionLevel = 0;
  uint32_t localLightLevel = 0;  // rays per pixel = the described ones / 2^level
  uint64_t measurements = 0;     // finished frames taken in
  uint64_t levelSteps = 0;       // level changes so far
};

// Per-pass measurements of the latest recordings whose frames have finished (zero for what does not exist).
struct HybridStats {
  PassStats shadow, shadowDenoise, ao, aoDenoise, reflection, localLights, localLightsDenoise, reflectionDenoise;
  // The change masks ("Change resets"): recorded only on frames with a known change, so this is the latest such
  // frame's (PassStats::frame says which); not in totalGpuMs(), which is this frame's.
  PassStats changeMasks;
  // The whole record() (the TLAS and pending acceleration-structure work included): what HybridEffectsDesc::budgetMs
  // holds. Its frame may be later than the passes'. rays = 0.
  PassStats hook;
  FrameBudgetStats budget;
  double totalGpuMs() const {
    return shadow.gpuMs + shadowDenoise.gpuMs + ao.gpuMs + aoDenoise.gpuMs + reflection.gpuMs + localLights.gpuMs +
           localLightsDenoise.gpuMs + reflectionDenoise.gpuMs;
  }
  uint64_t totalRays() const { return shadow.rays + ao.rays + reflection.rays + localLights.rays; }
};

class HybridEffects {
 public:
  // `service` builds the TLAS when a frame gives instances instead of a TLAS; nullptr = every frame brings
  // its own TLAS. The description's passes are created now, with their outputs when it has a size (else the
  // first record() makes them).
  static Result<std::unique_ptr<HybridEffects>> create(Context& context, AccelerationStructureService* service,
                                                       const HybridEffectsDesc& desc = {});
  ~HybridEffects();
  HybridEffects(const HybridEffects&) = delete;
  HybridEffects& operator=(const HybridEffects&) = delete;

  // Switches effects and settings between frames: passes of newly enabled effects are created now (with their
  // outputs, when the description has a size), those of disabled effects retired (see Lifetime). Validated
  // first: on an error nothing changes.
  Status setDesc(const HybridEffectsDesc& desc);
  // The G-buffer's new size: re-allocates the outputs (desc().width/height become it; the history restarts).
  // Views of the old outputs stay valid for the frames already recorded, and generation moves.
  Status resize(uint32_t width, uint32_t height);
  Status applyPreset(Preset preset) { return setDesc(withPreset(desc(), preset)); }
  const HybridEffectsDesc& desc() const;

  // The engine's materials and texture views (material_table.h): reflection hits shade with them, and shadow,
  // AO and reflection rays alpha-test the meshes registered with MeshDesc::nonOpaque through them (Mask
  // cut-outs, stochastic Blend). One table shared by every pass, in GPU memory only while an effect is enabled
  // (validated now when one is, else when one is enabled); the views must stay valid until the next call.
  // Without a call every instance is white and opaque.
  Status setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures);

  // Records the enabled effects (see Order above); with none enabled, only the neutral images' first clear.
  // On an error the engine keeps its own lighting terms this frame (see HybridOutputs).
  Status record(VkCommandBuffer cmd, const HybridFrame& frame);
  const HybridOutputs& outputs() const;
  const TlasInfo& lastTlas() const;  // the TLAS the latest record() traced
  // Forget the denoisers' history (camera cut, scene change): shadows, AO, local lights and reflections.
  void resetHistory();
  // The change mask of one effect (kEffectShadows, kEffectAo, kEffectLocalLights or kEffectReflections) that the
  // latest record() wrote: R8_UNORM, 1 = the effect's history restarts there, in SHADER_READ_ONLY_OPTIMAL until the
  // next record(). image == VK_NULL_HANDLE when that record() had no known change for it (or the effect has no
  // denoiser). For debug views and tests.
  EffectImage changeMask(EffectSet effect) const;

  HybridStats stats() const;
  // Device memory of the Context's pass categories (ShaderTables, PassImages, PassBuffers; the other
  // categories are 0): this object's passes and denoisers, plus any pass the engine created itself on the same
  // Context. `allocations` counts the whole Context's.
  MemoryStats memoryStats() const;
  // The same categories of this object's own memory by effect (EffectMemoryStats).
  EffectMemoryStats memoryByEffect() const;

  // The passes, for tools that want more than outputs() (nullptr where the effect is off).
  const ShadowPass* shadowPass() const;
  const AoPass* aoPass() const;
  const ReflectionPass* reflectionPass() const;
  const ManyLightPass* localLightPass() const;
  const Denoiser* shadowDenoiser() const;
  const Denoiser* aoDenoiser() const;
  const Denoiser* localLightDenoiser() const;  // nullptr unless Stochastic local lights are denoised
  const Denoiser* reflectionDenoiser() const;  // nullptr unless reflections are denoised

  struct Impl;

 private:
  explicit HybridEffects(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
