// Raybridge adapter for the sample forward engine (samples/engine): the only code that knows both.
//
// Implemented:
//  [x] Device setup: Raybridge's device extensions and feature chain go into EngineConfig (configureEngine).
//  [x] rb::Context on the engine's device, instance, queue family and kFramesInFlight.
//  [x] Engine meshes registered with the acceleration-structure service from the engine's own buffers (device
//      addresses, no copies), with their normals and UVs (interleaved attribute buffer) for reflection hits.
//  [x] Animation: every deforming instance (skinned, morphed) is a dynamic BLAS over the engine's deformed
//      buffers, updated every frame; node animation moves TLAS instances. With an async DynamicBuildMode the
//      refits and rebuilds run on the engine's async compute queue (EngineConfig::requestAsyncComputeQueue),
//      waiting on the engine's deform timeline; the frame's submission waits for what the TLAS needs
//      (PrepassHookInfo::submitWaits) and the next deformation for the SDK's reads (deformWaits).
//  [x] One TLAS per frame over the scene instances, camera-relative (originOffset = camera position), with
//      shading records (vertex data + material per instance) only while reflections are on.
//  [x] The engine's pre-pass described as an rb::GBufferDesc (shading or geometric normals; roughness in
//      normalRoughness.w).
//  [x] Effects, each a flag; only enabled effects have passes and images (created/destroyed at run time):
//      shadows     -> rb::ShadowPass [-> rb::Denoiser when soft] -> LightingInputs::sunVisibility
//      AO          -> rb::AoPass [-> rb::Denoiser]                -> LightingInputs::ambientOcclusion
//      reflections -> rb::ReflectionPass (engine materials)       -> LightingInputs::reflection
//  [x] Quality presets (Low / Medium / High / Ultra and single-effect presets), see presetDesc().
//  [x] Material textures in reflection hits: base colour (the engine's sRGB views) and metallic-roughness
//      (its UNORM views) from Engine::textures(). rb::Material has no emissive texture: an emissive texture
//      is folded into the emissive factor as its average texel.
//
// Where it sits in the engine's frame (everything is recorded into the engine's command buffer; the adapter
// never submits and never waits, except in its destructor):
//   shadow map -> depth+normal pre-pass -> [pre-pass hook: Context::beginFrame, BLAS builds, TLAS build,
//   shadows (+denoise), AO (+denoise), reflections] -> forward lighting (samples the outputs) -> tonemap
//
// Layouts: the pre-pass images are read in the layouts the engine hands them over (depth DEPTH_READ_ONLY_OPTIMAL,
// normals SHADER_READ_ONLY_OPTIMAL) and left so; effect outputs are left in SHADER_READ_ONLY_OPTIMAL, as
// LightingInputs requires.
//
// Usage:
//   rb::RequiredFeatures features;                      // must outlive Engine::create()
//   sample_engine::EngineConfig config;
//   rbAdapter::configureEngine(config, features);
//   auto engine = sample_engine::Engine::create(config).value;
//   engine->loadScene(scene);
//   auto adapter = rbAdapter::Adapter::create(*engine, {}).value;   // after loadScene (or call syncScene())
//   adapter->applyPreset(rbAdapter::Preset::High);                  // optional: effects + quality knobs
//   engine->setPrepassHook(adapter->prepassHook());
//   adapter->settings().lightingFrom(params);           // sun radiance and sky, for reflection hits
//   engine->renderFrame(params);                        // as before
//
// Thread safety: an Adapter is used from the thread that renders with its engine, like the engine itself.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <raybridge/raybridge.h>

#include "sample_engine/engine.h"

namespace rbAdapter {

// The effects an adapter runs. Passes (and their images and buffers) of effects that are not in the set do
// not exist, so they hold no memory; changing the set at run time creates or releases them.
enum Effect : uint32_t {
  kEffectShadows = 1u << 0,      // ray-traced sun visibility -> LightingInputs::sunVisibility
  kEffectAo = 1u << 1,           // ray-traced ambient occlusion -> LightingInputs::ambientOcclusion
  kEffectReflections = 1u << 2,  // ray-traced reflections -> LightingInputs::reflection
};
using EffectSet = uint32_t;
inline constexpr EffectSet kAllEffects = kEffectShadows | kEffectAo | kEffectReflections;

// "shadows,ao,reflections" (any order, "" = none) <-> EffectSet. parseEffects returns an error naming the bad
// item, or "" on success.
std::string effectsToString(EffectSet effects);
std::string parseEffects(std::string_view text, EffectSet& out);

// The normal the passes shade with (GBufferDesc::normal).
enum class GBufferNormals : uint8_t {
  Shading = 0,  // default: the pre-pass's normal-mapped normal (roughness in .w); geometric normal offsets rays
  Geometric,    // the triangle normal for both (conformance checks, comparisons with reference tracers)
};

struct AdapterConfig {
  EffectSet effects = kEffectShadows;  // default: shadows; 0 = no pass, no BLAS, no TLAS (only frame pacing)
  GBufferNormals normals = GBufferNormals::Shading;  // default Shading
  // Zero = the SDK's defaults (64 MiB scratch, no budget, dynamic BLAS work in the frame). With an async
  // dynamicMode and no asyncQueue, the engine's async compute queue is handed over.
  rb::AsServiceDesc accelerationStructures;
};

// Per-frame knobs; change them between frames through Adapter::settings(). Zeros mean the SDK's defaults.
struct FrameSettings {
  bool enabled = true;                   // false = record nothing: the engine uses its own lighting terms
  bool denoise = true;                   // denoise soft shadows and AO (the raw images stay available)
  // false = the BLASes of deforming instances keep their last pose (a paused animation costs no BLAS work).
  bool updateDeformedMeshes = true;
  // Shadows.
  float sunAngularRadiusDegrees = 0.0f;  // 0 = hard shadows (one ray per pixel, never denoised)
  uint32_t shadowRaysPerPixel = 0;       // soft shadows only; 0 = the SDK's default (4)
  // Ambient occlusion.
  uint32_t aoRaysPerPixel = 0;           // 0 = 4
  float aoRange = 0.0f;                  // world units; 0 = 1.0
  rb::AoEstimator aoEstimator = rb::AoEstimator::Binary;
  // Reflections.
  // Default 0.5 (the SDK's is 0.3), so the demo's brushed copper (0.45) gets traced reflections. Untraced
  // pixels (alpha 0 in the reflection image) keep the engine's own environment term (sky or probe).
  float reflectionRoughnessThreshold = 0.5f;
  uint32_t reflectionRaysPerPixel = 4;  // glossy pixels; the reflection is not denoised (0 = 1)
  // Light that reflection hits are shaded with. The hook does not receive it from the engine: set it from
  // the frame's FrameParams (lightingFrom) whenever the sun or sky change.
  glm::vec3 sunRadiance{1.0f * 3.5f, 0.96f * 3.5f, 0.9f * 3.5f};  // sun colour * intensity (engine default)
  glm::vec3 skyColor{0.45f, 0.62f, 0.9f};
  float ambientIntensity = 0.4f;
  rb::DenoiseSettings denoiser;  // shared by the shadow and AO denoisers

  void lightingFrom(const sample_engine::FrameParams& params) {
    sunRadiance = params.sun.color * params.sun.intensity;
    skyColor = params.skyColor;
    ambientIntensity = params.ambientIntensity;
  }
};

// Quality presets (the thesis's table) and single-effect presets.
enum class Preset : uint8_t {
  Low = 0,          // hard shadows, AO 4 rays
  Medium,           // soft shadows 4 rays, AO 4 rays
  High,             // Medium + reflections
  Ultra,            // soft shadows 8 rays, AO 16 rays, reflections
  ShadowsOnly,      // soft shadows 4 rays
  AoOnly,           // AO 4 rays
  ReflectionsOnly,  // reflections
};
inline constexpr float kDefaultSoftSunRadiusDegrees = 0.5f;

struct PresetDesc {
  EffectSet effects = 0;
  bool softShadows = false;
  uint32_t shadowRaysPerPixel = 1;
  uint32_t aoRaysPerPixel = 0;  // 0 when the preset has no AO
};
PresetDesc presetDesc(Preset preset);
const char* toString(Preset preset);  // "low", "medium", "high", "ultra", "shadows", "ao", "reflections"
std::optional<Preset> parsePreset(std::string_view name);

// (a) Before Engine::create(): adds Raybridge's device extensions, merges its core (Vulkan 1.1/1.2/1.3)
// features into EngineConfig::extraFeatures11/12/13 and chains its other feature structs into
// EngineConfig::deviceFeaturesPNext (in front of whatever was there). `features` holds that chain and must stay
// alive until Engine::create() returns.
void configureEngine(sample_engine::EngineConfig& config, rb::RequiredFeatures& features);

// Measurements of the latest recorded passes whose frame has finished (zero for passes that do not exist).
struct EffectStats {
  rb::PassStats shadow, shadowDenoise, ao, aoDenoise, reflection;
};

// The images the latest recorded frame produced (VK_NULL_HANDLE where not produced), all left in
// SHADER_READ_ONLY_OPTIMAL: R16_SFLOAT for shadow/AO, R16G16B16A16_SFLOAT for the reflection.
struct FrameImages {
  VkImage shadowRaw = VK_NULL_HANDLE, shadow = VK_NULL_HANDLE;  // shadow = what the lighting sampled
  VkImage aoRaw = VK_NULL_HANDLE, ao = VK_NULL_HANDLE;          // ao = what the lighting sampled
  VkImage reflection = VK_NULL_HANDLE;
};

class Adapter {
 public:
  // (b) + (c): creates the rb::Context on the engine's device, the AS service and the passes of
  // config.effects, and registers the engine's current scene. Never throws; the error names what failed.
  static sample_engine::Result<std::unique_ptr<Adapter>> create(sample_engine::Engine& engine,
                                                                const AdapterConfig& config = {});
  // Waits for the engine's GPU work (Engine::waitIdle), because destroying the AS service and the Context
  // releases at once what the engine's frames in flight may still use (passes alone would not need it: the
  // SDK defers their release). Remove the hook (engine.setPrepassHook({})) first if the engine outlives the
  // adapter and keeps rendering.
  ~Adapter();
  Adapter(const Adapter&) = delete;
  Adapter& operator=(const Adapter&) = delete;

  // Call after every Engine::loadScene(): releases the previous meshes and registers the new ones (and the
  // materials, with reflections). Builds are queued and recorded by the next frames.
  sample_engine::Status syncScene();

  // Changes the effect set between frames: passes of newly enabled effects are created now (memory for their
  // images follows on the next frame), those of disabled effects are destroyed now; the SDK frees their
  // Vulkan objects and memory once the frames in flight that used them are done (or at releaseAfterIdle()).
  sample_engine::Status setEffects(EffectSet effects);
  EffectSet effects() const;
  // setEffects(presetDesc(p).effects) plus the preset's rays per pixel; soft presets use
  // `sunAngularRadiusDegrees` (hard presets set 0). Other settings are left as they are.
  sample_engine::Status applyPreset(Preset preset, float sunAngularRadiusDegrees = kDefaultSoftSunRadiusDegrees);

  // (d) The pre-pass hook: engine.setPrepassHook(adapter->prepassHook()). It calls recordFrame().
  sample_engine::PrepassHook prepassHook();
  // What the hook does, for engines (or tools) that install their own hook and call it from there.
  // Contract check: the sample engine waits on the frame slot's fence before recording, so every frame it
  // submitted before the previous kFramesInFlight beginFrame() calls is finished, as Context::beginFrame needs.
  void recordFrame(const sample_engine::PrepassHookInfo& info, sample_engine::LightingInputs& inputs);
  // The engine is idle (after Engine::waitIdle): the SDK frees what destroyed passes retired now
  // (Context::releaseAfterIdle).
  void releaseAfterIdle();
  // Forget the denoisers' history (camera cut, scene change).
  void resetHistory();

  FrameSettings& settings();
  // The first error a frame ran into ("" = none). Such a frame keeps the engine's own lighting terms.
  const std::string& lastError() const;

  // The SDK objects, for statistics and for tools (e.g. reading the output images back).
  rb::Context& context();
  rb::AccelerationStructureService& accelerationStructures();
  const rb::ShadowPass* shadowPass() const;          // nullptr unless kEffectShadows
  const rb::AoPass* aoPass() const;                  // nullptr unless kEffectAo
  const rb::ReflectionPass* reflectionPass() const;  // nullptr unless kEffectReflections
  const rb::Denoiser* shadowDenoiser() const;        // nullptr unless soft shadows are denoised
  const rb::Denoiser* aoDenoiser() const;            // nullptr unless AO is denoised
  EffectStats stats() const;
  const FrameImages& lastImages() const;     // images of the latest recorded frame
  const rb::TlasInfo& lastTlas() const;      // TLAS of the latest recorded frame
  uint32_t sceneInstances() const;           // instances handed to the TLAS each frame

  struct Impl;

 private:
  explicit Adapter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rbAdapter
