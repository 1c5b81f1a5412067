// Types shared by the effect passes: lights and per-pass measurements.
//
// Thread safety: plain data.
#pragma once

#include <cstdint>

namespace rb {

enum class LightType : uint8_t {
  Directional = 0,  // default: the sun
  Point,
  Spot,
};

// Limits every effect checks a Light against (one validator, the same message wherever a light is taken).
// A directional light's disk below 45 degrees of angular radius (the cone-sampling of soft shadows assumes it):
inline constexpr float kMaxLightAngularRadiusDegrees = 45.0f;
// A spot's half-angle when Light::spotOuterAngleDegrees is 0, and its largest value:
inline constexpr float kDefaultSpotOuterAngleDegrees = 45.0f;
inline constexpr float kMaxSpotOuterAngleDegrees = 90.0f;
// Rays per pixel any effect traces for one signal at most (shadow and AO settings).
inline constexpr uint32_t kMaxRaysPerPixel = 4096;

struct Light {
  LightType type = LightType::Directional;
  // Directional: direction towards the light (need not be normalised). Spot: the direction the spot shines.
  // All zero = the default: a sun straight overhead (0, 1, 0), a spot shining straight down (0, -1, 0).
  float direction[3] = {0.0f, 0.0f, 0.0f};
  double position[3] = {0.0, 0.0, 0.0};  // point and spot: world-space position
  // Directional: angular radius of the light's disk in degrees; 0 = hard shadows (one ray, no noise).
  float angularRadiusDegrees = 0.0f;
  float radius = 0.0f;  // point and spot: radius of the emitting disk facing the surface; 0 = hard shadows
  float range = 0.0f;   // point and spot: beyond it a surface is unlit and traces nothing; 0 = unlimited
  float spotOuterAngleDegrees = 0.0f;  // spot: half-angle of the cone; 0 = kDefaultSpotOuterAngleDegrees
};

// A world-space box where the world changed this frame (HybridFrame::changedBoxes, ReflectionSettings::changedBoxes):
// min <= max per axis, finite. Plain value.
struct ChangedBox {
  double min[3] = {0.0, 0.0, 0.0};
  double max[3] = {0.0, 0.0, 0.0};
};

// What one recorded pass did, resolved once its frame has finished on the GPU.
struct PassStats {
  uint64_t frame = 0;  // Context::frameIndex() when recorded; 0 = nothing resolved yet
  double gpuMs = 0.0;  // GPU time between the pass's first and last command
  uint64_t rays = 0;   // rays traced, counted by the shaders
  // Any-hit shader invocations (alpha tests on non-opaque geometry, MeshDesc::nonOpaque); 0 when every mesh the
  // rays reached is opaque.
  uint64_t anyHitInvocations = 0;
  // A pass with a tile classifier (ShadowPass; AoPass with AoSettings::schedule.convergedTiles): of the image's
  // 8x8-pixel tiles, those traced and those skipped (pixels that all needed no ray, written without tracing, or
  // converged). Both 0 when the pass ran without one.
  uint64_t tilesTraced = 0;
  uint64_t tilesSkipped = 0;
  // Of tilesSkipped, those that needed rays but were skipped because their history had converged
  // (ShadowSettings::schedule.convergedTiles, AoSettings::schedule.convergedTiles), and the rays their pixels would
  // have traced at the uniform rays per pixel.
  uint64_t tilesConverged = 0;
  uint64_t raysSaved = 0;
  uint64_t tilesTotal() const { return tilesTraced + tilesSkipped; }
  double raysPerSecond() const { return gpuMs > 0.0 ? double(rays) / (gpuMs * 1e-3) : 0.0; }
};

}  // namespace rb
