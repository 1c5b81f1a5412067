// GPU layout of the KHR lights (shaders/local_lights.glsl) and the CPU side of placing, ranking and shadowing
// them for one frame. The recording itself is Engine::Impl's (local_lights.cpp).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "sample_engine/engine.h"

namespace sample_engine::detail {

// Shadow views of the local shadow maps: six per shadowed light at most (points, wide spots).
inline constexpr uint32_t kMaxLocalShadowViews = kMaxShadowedLocalLights * 6;
// A spot light whose outer cone is wider than this gets six cube views instead of one perspective view
// (a single perspective map of a cone near pi/2 would spread its texels thin).
inline constexpr float kMaxSingleViewSpotCone = 1.04719755f;  // pi / 3

// std430 mirror of LocalLight in shaders/local_lights.glsl.
struct GpuLocalLight {
  glm::vec4 positionRange;  // xyz: position - eye, w: range (0 = unlimited)
  glm::vec4 directionType;  // xyz: travel direction, w: PunctualLight::Type
  glm::vec4 radiance;       // rgb: color * intensity
  glm::vec4 cone;           // x: cos(outer), y: 1 / (cos(inner) - cos(outer)), z: shadow slot (-1 = none)
};
static_assert(sizeof(GpuLocalLight) == 64);

// std140 mirror of LocalShadows in shaders/local_lights.glsl.
struct GpuLocalShadows {
  glm::uvec4 counts;                         // x: PCF taps (0 = no local shadow maps this frame)
  glm::vec4 params;                          // x: 1 / map size, y: normal offset in texels
  glm::vec4 slots[kMaxShadowedLocalLights];  // x: first view, y: views, z: texel footprint, w: 1 = orthographic
  glm::mat4 viewProj[kMaxLocalShadowViews];
};
static_assert(offsetof(GpuLocalShadows, slots) == 32);
static_assert(offsetof(GpuLocalShadows, viewProj) == 32 + 16 * kMaxShadowedLocalLights);

// Places every light of `scene` with this frame's node transforms (nodeWorld: per Scene::nodes entry).
void placeLights(const Scene& scene, std::span<const glm::mat4> nodeWorld, std::vector<FrameLight>& out);

// The unshadowed irradiance estimate that ranks lights for shadow maps: luminance(color) * intensity, divided
// for point and spot lights by the squared distance to `eye` (at least 1 world unit), without the spot cone,
// the range window or any cosine (a spot that points away from the eye may still light what it sees).
double shadowRank(const FrameLight& light, const glm::dvec3& eye);

// Indices of the `count` strongest lights by shadowRank (ties: lower index first); lights with a rank of 0
// (black or zero intensity) never get a map.
std::vector<uint32_t> strongestLights(std::span<const FrameLight> lights, const glm::dvec3& eye, uint32_t count);

// One shadowed light's views, camera-relative.
struct LocalShadowViews {
  uint32_t count = 0;  // 1 (spot, directional) or 6 (point, wide spot: +X -X +Y -Y +Z -Z)
  glm::mat4 viewProj[6]{};
  float footprint = 0.0f;  // see GpuLocalShadows::slots
  bool orthographic = false;
};
// `bounds`: the scene's rest-pose bounds (near/far planes, the directional light's box). `taps`: PCF kernel, to
// widen the cube faces so the kernel of a lookup near a face's edge stays inside that face.
LocalShadowViews shadowViewsFor(const FrameLight& light, const Bounds& bounds, const glm::dvec3& eye, uint32_t mapSize,
                                uint32_t taps);

GpuLocalLight gpuLight(const FrameLight& light, const glm::dvec3& eye, int shadowSlot);

}  // namespace sample_engine::detail
