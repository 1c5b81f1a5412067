// Raybridge adapter for the sample forward engine (samples/engine): the only code that knows both.
//
// Implemented:
//  [x] Device setup: Raybridge's device extensions and feature chain go into EngineConfig (configureEngine).
//  [x] rb::Context on the engine's device, instance, queue family and kFramesInFlight.
//  [x] Engine meshes registered with the acceleration-structure service from the engine's own buffers (device
//      addresses, no copies; the CPU copies feed the content hash, so identical meshes share one BLAS).
//  [x] One TLAS per frame over the scene instances, camera-relative (originOffset = camera position).
//  [x] The engine's pre-pass described as an rb::GBufferDesc (shading or geometric normals).
//  [x] Effect: ray-traced sun shadows (hard or soft) -> LightingInputs::sunVisibility.
//  [ ] Effects: ambient occlusion -> LightingInputs::ambientOcclusion, reflections -> LightingInputs::reflection
//      (next SDK passes; they plug in like the shadows: one flag, one pass, one LightingInputs field).
//
// Where it sits in the engine's frame (everything is recorded into the engine's command buffer; the adapter
// never submits and never waits, except once in its destructor):
//   shadow map -> depth+normal pre-pass -> [pre-pass hook: Context::beginFrame, BLAS builds, TLAS build,
//   effect passes] -> forward lighting (samples the effect outputs) -> tonemap
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
//   engine->setPrepassHook(adapter->prepassHook());
//   engine->renderFrame(params);                        // as before
//
// Thread safety: an Adapter is used from the thread that renders with its engine, like the engine itself.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <raybridge/raybridge.h>

#include "sample_engine/engine.h"

namespace rbAdapter {

// The effects an adapter creates. Passes of effects that are not in the set are never created, so they hold
// no memory (rb::MemoryCategory::PassImages stays 0 without any effect).
enum Effect : uint32_t {
  kEffectShadows = 1u << 0,  // ray-traced sun visibility -> LightingInputs::sunVisibility
  // kEffectAmbientOcclusion = 1u << 1, kEffectReflections = 1u << 2: reserved for the next SDK passes.
};
using EffectSet = uint32_t;

// The normal the passes shade with (GBufferDesc::normal).
enum class GBufferNormals : uint8_t {
  Shading = 0,  // default: the pre-pass's normal-mapped normal (roughness in .w); geometric normal offsets rays
  Geometric,    // the triangle normal for both (conformance checks, comparisons with reference tracers)
};

struct AdapterConfig {
  EffectSet effects = kEffectShadows;  // default: shadows; 0 = no pass, no BLAS, no TLAS (only frame pacing)
  GBufferNormals normals = GBufferNormals::Shading;  // default Shading
  rb::AsServiceDesc accelerationStructures;          // zero = the SDK's defaults (64 MiB scratch, no budget)
};

// Per-frame knobs; change them between frames through Adapter::settings().
struct FrameSettings {
  bool enabled = true;                   // false = record nothing: the engine uses its own shadow map
  float sunAngularRadiusDegrees = 0.0f;  // 0 = hard shadows (one ray per pixel)
  uint32_t shadowRaysPerPixel = 0;       // soft shadows only; 0 = the SDK's default (4)
};

// (a) Before Engine::create(): adds Raybridge's device extensions, merges its core (Vulkan 1.1/1.2/1.3)
// features into EngineConfig::extraFeatures11/12/13 and chains its other feature structs into
// EngineConfig::deviceFeaturesPNext (in front of whatever was there). `features` holds that chain and must stay
// alive until Engine::create() returns.
void configureEngine(sample_engine::EngineConfig& config, rb::RequiredFeatures& features);

class Adapter {
 public:
  // (b) + (c): creates the rb::Context on the engine's device, the AS service and the passes of
  // config.effects, and registers the engine's current scene. Never throws; the error names what failed.
  static sample_engine::Result<std::unique_ptr<Adapter>> create(sample_engine::Engine& engine,
                                                                const AdapterConfig& config = {});
  // Waits for the engine's GPU work (Engine::waitIdle) before releasing the SDK objects. Remove the hook
  // (engine.setPrepassHook({})) first if the engine outlives the adapter and keeps rendering.
  ~Adapter();
  Adapter(const Adapter&) = delete;
  Adapter& operator=(const Adapter&) = delete;

  // Call after every Engine::loadScene(): releases the previous meshes and registers the new ones. Builds are
  // queued and recorded by the next frames.
  sample_engine::Status syncScene();

  // (d) The pre-pass hook: engine.setPrepassHook(adapter->prepassHook()). It calls recordFrame().
  sample_engine::PrepassHook prepassHook();
  // What the hook does, for engines (or tools) that install their own hook and call it from there.
  // Contract check: the sample engine waits on the frame slot's fence before recording, so every frame it
  // submitted before the previous kFramesInFlight beginFrame() calls is finished, as Context::beginFrame needs.
  void recordFrame(const sample_engine::PrepassHookInfo& info, sample_engine::LightingInputs& inputs);

  FrameSettings& settings();
  // The first error a frame ran into ("" = none). Such a frame keeps the engine's own lighting terms.
  const std::string& lastError() const;

  // The SDK objects, for statistics and for tools (e.g. reading the visibility image back).
  rb::Context& context();
  rb::AccelerationStructureService& accelerationStructures();
  const rb::ShadowPass* shadowPass() const;  // nullptr unless kEffectShadows
  const rb::TlasInfo& lastTlas() const;      // TLAS of the latest recorded frame
  uint32_t sceneInstances() const;           // instances handed to the TLAS each frame

  struct Impl;

 private:
  explicit Adapter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rbAdapter
