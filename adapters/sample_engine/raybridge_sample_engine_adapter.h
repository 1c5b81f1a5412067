// Raybridge adapter for the sample forward engine (samples/engine): the only code that knows both. It sets up
// the device (configureEngine), registers the engine's meshes from its own buffers (deforming instances as
// dynamic BLASes, on the engine's async compute queue in the async modes), describes its pre-pass as an
// rb::GBufferDesc, hands its KHR_lights_punctual lights to the local lights effect and lets an rb::HybridEffects
// front end record the effects, whose outputs become the engine's LightingInputs. Frame: shadow map -> pre-pass ->
// [hook: beginFrame, BLAS work, TLAS, effects] -> lighting.
// Ray-traced mode (AdapterConfig::rayTraced, with FrameParams::externalColor): no G-buffer and no raster
// lighting; the hook builds the TLAS and an rb::PrimaryShadingPass shades one primary ray per pixel (sun with a
// shadow ray, sky ambient, emission, the punctual lights) straight into the engine's HDR target.
//
//   rb::RequiredFeatures features;                       // must outlive Engine::create()
//   rb::OptionalFeatures optional;                       // likewise; optional (shader execution reordering)
//   rbAdapter::configureEngine(config, features, &optional);  // config: the engine's EngineConfig
//   auto engine = sample_engine::Engine::create(config).value;
//   auto adapter = rbAdapter::Adapter::create(*engine, {.preset = rb::Preset::High}).value;  // after loadScene
//   engine->setPrepassHook(adapter->prepassHook());      // then render as before
//   adapter->effects().applyPreset(rb::Preset::Ultra);   // any time between frames
//
// Thread safety: an Adapter is used from the thread that renders with its engine, like the engine itself.
#pragma once

#include <memory>
#include <string>

#include <raybridge/raybridge.h>

#include "sample_engine/engine.h"

namespace rbAdapter {

struct AdapterConfig {
  // What runs: `effects`, with the preset's effect set and ray counts when preset is not None. Default: nothing
  // (no pass, no TLAS). Change it later through effects().
  rb::Preset preset = rb::Preset::None;
  rb::HybridEffectsDesc effects;
  // The normal the passes shade with: false = the pre-pass's normal-mapped one (the geometric normal offsets
  // rays); true = the triangle normal (conformance checks against reference tracers; reflections keep shading).
  bool geometricNormals = false;
  // Zero = the SDK's defaults. With an async dynamicMode and no asyncQueue, the engine's async compute queue
  // is handed over (VK_NULL_HANDLE on one-queue devices: the SDK falls back to in-frame work).
  rb::AsServiceDesc accelerationStructures;
  // Pure ray tracing instead of effects on the raster frame: frames must set FrameParams::externalColor, and
  // `effects` must be empty (they need the G-buffer that mode does not draw; create() fails naming them).
  bool rayTraced = false;
};

struct FrameSettings {  // change them between frames through Adapter::settings()
  bool enabled = true;  // false = record nothing: the engine uses its own lighting terms (ray-traced mode: the sky)
  bool updateDeformedMeshes = true;  // false = deforming BLASes keep their pose (a paused animation costs nothing)
};

// Before Engine::create(): Raybridge's device extensions and features (held by `features`) into the config. With
// `optional` (which must outlive Engine::create() too), also the optional ones where the chosen device has them
// (shader execution reordering for reflections); Adapter::create() then tells the context what was enabled.
void configureEngine(sample_engine::EngineConfig& config, rb::RequiredFeatures& features,
                     rb::OptionalFeatures* optional = nullptr);

class Adapter {
 public:
  // The rb::Context on the engine's device, the AS service, the front end; registers the current scene.
  static sample_engine::Result<std::unique_ptr<Adapter>> create(sample_engine::Engine& engine,
                                                                const AdapterConfig& config = {});
  // Waits for the engine's GPU work (Engine::waitIdle), because ~Context requires an idle device (the passes
  // alone would not: the SDK defers their release). Remove the hook first if the engine keeps rendering.
  ~Adapter();  // not copyable (unique_ptr member)

  // After every Engine::loadScene(): releases the previous meshes, registers the new ones and the materials.
  sample_engine::Status syncScene();

  sample_engine::PrepassHook prepassHook();  // calls recordFrame()
  // What the hook does. The engine waits on the frame slot's fence first, as Context::beginFrame requires.
  void recordFrame(const sample_engine::PrepassHookInfo& info, sample_engine::LightingInputs& inputs);

  FrameSettings& settings();
  // The first error a frame ran into ("" = none). Such a frame keeps the engine's own lighting terms.
  const std::string& lastError() const;

  // The SDK objects: the front end (effects, presets, outputs, statistics), the AS service, the context.
  rb::HybridEffects& effects();
  const rb::HybridEffects& effects() const;
  // The ray-traced mode's pass (outputs: its distance image; stats), nullptr otherwise.
  const rb::PrimaryShadingPass* primaryShading() const;
  // The TLAS the latest frame traced (either mode).
  const rb::TlasInfo& lastTlas() const;
  rb::Context& context();
  rb::AccelerationStructureService& accelerationStructures();

  struct Impl;

 private:
  explicit Adapter(std::unique_ptr<Impl> impl);
  void recordRayTraced(const sample_engine::PrepassHookInfo& info);  // recordFrame() in ray-traced mode
  std::unique_ptr<Impl> impl_;
};

}  // namespace rbAdapter
