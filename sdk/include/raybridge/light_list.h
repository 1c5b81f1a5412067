// The engine's light list on the GPU: uploaded once a frame, read by every effect lit by it. The many-light pass
// (ManyLightFrame::lightList), reflection hits (ReflectionSettings::lights) and the pure ray-traced
// mode (PrimaryShadingSettings::lights) read the same upload, so the lights are checked, converted and copied once
// and the effects stay side by side: none of them reads another's state. HybridEffects owns one for its effects.
//
// record() checks every light first (one validator for every effect, see effects.h's rb::Light); on error nothing
// is recorded and the message names the light's index and field. The lights are copied into a per-frame ring (one
// slot per frame in flight) and from there into a device buffer by the commands record() adds, so the caller's
// array may change right after the call. Record it before the passes that read it, in the same command buffer or
// an earlier one of the same frame; a pass given a list not recorded this frame, or recorded for another TLAS
// space (TlasInfo::originOffset), refuses it with a named error.
//
// Lifetime: destroying it is safe while frames that read it are in flight: its buffers are handed to the Context's
// deferred release (see context.h). Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/context.h>
#include <raybridge/effects.h>
#include <raybridge/result.h>

#include <memory>
#include <span>

namespace rb {

inline constexpr uint32_t kMaxLights = 65536;
inline constexpr uint64_t kNeverRecorded = UINT64_MAX;  // LightListInfo::frame before the first record()

// One light of the engine's list: the geometry and softness of rb::Light, with colour and intensity in
// KHR_lights_punctual's units. Defaults are glTF's (colour white, intensity 1, inner cone angle 0).
struct LightSource {
  // type, direction (directional: towards the light; spot: the direction it shines), position, range (0 =
  // unlimited: no range window), spotOuterAngleDegrees (0 = 45), and the softness: radius (point, spot) or
  // angularRadiusDegrees (directional), 0 = hard shadows.
  Light light{};
  float color[3] = {1.0f, 1.0f, 1.0f};  // linear RGB, >= 0
  float intensity = 1.0f;               // candela (point, spot) or lux (directional), finite and >= 0
  float spotInnerAngleDegrees = 0.0f;   // spot: full intensity inside it; in [0, outer]
};

// What the passes lit by the list read of its latest record(). The buffer's layout is the SDK's own (64 bytes a
// light, not part of the API); the rest is for checks and statistics.
struct LightListInfo {
  VkBuffer buffer = VK_NULL_HANDLE;          // device-local; readable by compute and ray tracing shaders after record()
  uint32_t count = 0;                        // lights in it
  uint64_t frame = kNeverRecorded;           // Context::frameIndex() of the latest record()
  double originOffset[3] = {0.0, 0.0, 0.0};  // the TLAS space its positions are in (TlasInfo::originOffset)
};

class LightList {
 public:
  static Result<std::unique_ptr<LightList>> create(Context& context);
  // Retires its buffers to the context, without waiting.
  ~LightList();

  // Checks `lights` (at most kMaxLights; may be empty) and records their upload, in the space of `tlas` (its
  // originOffset; the TLAS itself is not read). Once a frame (Context::frameIndex()): the frame's ring slot is
  // written on the host now and copied when the commands run, so a second record() in the same frame would
  // overwrite what the first one's copy reads; it is refused with a named error.
  Status record(VkCommandBuffer cmd, const TlasInfo& tlas, std::span<const LightSource> lights);
  LightListInfo info() const;

  struct Impl;

 private:
  explicit LightList(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
