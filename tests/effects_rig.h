// What the front-end tests record HybridEffects frames on: the conformance scene built into an acceleration-structure
// service and traced as a G-buffer from motionTestView, recorded with a soft sun and the tests' local lights.
// Declare it before the HybridEffects it feeds, so that the effects go first: its destructor destroys the scene.
#pragma once

#include <raybridge/raybridge.h>

#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "synthetic_gbuffer.h"

namespace rbtest {

class EffectsRig {
 public:
  // `roughness`: every surface's, in the G-buffer's normal image (0: mirrors).
  EffectsRig(GpuFixture& fx, uint32_t width, uint32_t height, float roughness = 0.0f);
  ~EffectsRig();
  EffectsRig(const EffectsRig&) = delete;
  EffectsRig& operator=(const EffectsRig&) = delete;

  rb::AccelerationStructureService& service() { return *service_; }
  // One frame of `effects`: the rig's G-buffer and instances, the sun 1 degree wide, `lights` as local lights.
  void record(rb::HybridEffects& effects, std::span<const rb::LightSource> lights = {});
  // One frame whose description `edit` changes first (for the error paths): record()'s status, unchecked.
  rb::Status recordEdited(rb::HybridEffects& effects, const std::function<void(rb::HybridFrame&)>& edit);

 private:
  GpuFixture& fx_;
  std::unique_ptr<rb::AccelerationStructureService> service_;
  BuiltScene built_;
  std::unique_ptr<GpuGBuffer> gbuffer_;
};

// `count` point lamps in a row over the conformance scene's boxes (range 6, intensity 4).
std::vector<rb::LightSource> lampRow(size_t count);

}  // namespace rbtest
