// Shadowed lighting from many lights at a fixed ray budget: the engine hands over its whole light list each
// frame (up to kMaxLights point, spot and directional lights), and the pass writes the shadowed diffuse
// irradiance at every G-buffer surface point, RGB, HDR:
//
//   E = sum over lights of  colour * intensity * max(dot(n, l), 0) * falloff * visibility
//   falloff: directional 1 (intensity in lux); point and spot 1 / d^2 (intensity in candela), times glTF's
//            range window clamp(1 - (d / range)^4, 0, 1) when range > 0, times for spots glTF's cone falloff
//            clamp((cos(angle) - cos(outer)) / (cos(inner) - cos(outer)), 0, 1)^2.
//
// No BRDF and no albedo: the engine multiplies by its diffuse colour (Lambert: albedo / pi * E).
//
// How (ManyLightSettings::mode):
//   Stochastic  a fixed number of shadow rays per pixel whatever the light count. Each ray keeps one of the
//               lights that can reach the pixel's screen tile in proportion to its unshadowed contribution there
//               and traces one shadow ray to it. The pixel weighs every listed light when its tile lists at most
//               ManyLightSettings::candidates (exactly proportional), else that many drawn uniformly from the list
//               (resampled importance sampling); the rays share the weighed candidates.
//               Unbiased in the mean; noisy per frame (give the output to a Denoiser made with
//               DenoiserDesc::signal = DenoiseSignal::Rgb). Where the tile holds no more lights than rays,
//               every light gets its own ray instead (exact, no noise).
//   Exact       one shadow ray per light that reaches the pixel: the reference, for few lights and tests.
// A culling pass first lists, per 16x16-pixel tile, the lights whose range and cone can reach the tile's surface
// points: lights that cannot reach a pixel cost nothing there (no candidate, no ray), sky pixels trace nothing.
// A tile reached by more than kMaxTileLights lights draws its candidates from the whole list instead (still
// unbiased, noisier).
//
// The lights come as a LightList the engine recorded this frame (shared with reflection hits and the pure
// ray-traced mode: light_list.h), or as the array itself, which record() then uploads into a list of the pass's own
// (copied, so the caller's array may change right after the call).
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipelines, buffers, output
// image and measurement objects are handed to the Context's deferred release (see context.h). Destroy it
// before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>
#include <raybridge/light_list.h>
#include <raybridge/material_table.h>
#include <raybridge/ray_schedule.h>

#include <memory>
#include <span>

namespace rb {

inline constexpr uint32_t kMaxTileLights = 256;     // lights one tile lists; more = candidates from all
inline constexpr uint32_t kManyLightTileSize = 16;  // pixels per tile side
inline constexpr uint32_t kDefaultLightRays = 1;    // shadow rays per pixel in Stochastic mode
// Lights weighed per pixel: up to this many in a tile, selection is exactly proportional to the unshadowed
// contribution; each costs a few ALU operations and no ray.
inline constexpr uint32_t kDefaultLightCandidates = 32;

enum class ManyLightMode : uint32_t {
  Stochastic = 0,  // default: ManyLightSettings::raysPerPixel rays whatever the light count
  Exact,           // one ray per light that reaches the pixel
};

struct ManyLightSettings {
  ManyLightMode mode = ManyLightMode::Stochastic;
  uint32_t raysPerPixel = 0;  // Stochastic: 0 = kDefaultLightRays; at most 64
  uint32_t candidates = 0;    // Stochastic: lights weighed per pixel; 0 = kDefaultLightCandidates; at most 64
  // Alpha-tested geometry (see ShadowSettings::materials); nullptr = every surface casts a solid shadow.
  const MaterialTable* materials = nullptr;
  // Stochastic: skip the 8x8-pixel tiles whose denoised irradiance (a DenoiseSignal::Rgb Denoiser, named in it) has
  // converged, as for soft shadows (raybridge/ray_schedule.h): maxNoise is relative to the irradiance's colour
  // (see there); their pixels hold kept-history marks (the reprojected mean, a = -1) instead of irradiance, and a
  // refreshed tile whose new rays disagree with its history is held and marked stale (a = 2: the denoiser drops it).
  // The launch stays one invocation per pixel; a skipped tile's return at once. Off by default: a moved light shows
  // on a converged tile up to refreshPeriod frames late. PassStats counts the tiles and raysPerPixel per skipped
  // surface pixel as rays saved (at most what it would have traced). The tile state takes 4 bytes per tile.
  // That is schedule.convergedTiles, with schedule.history: the one stage this pass allows (ray_schedule.h).
  RaySchedule schedule{};
};

// Fixed for the pass's life. Zero-initialised = images created at the first record().
struct ManyLightPassDesc {
  // Create the output images at width x height now (as prepare()), so that outputs() names them and the first
  // record() allocates nothing; 0 x 0 = at the first record(). Both or neither.
  uint32_t width = 0, height = 0;
};

// What one record() traces. The G-buffer and TLAS have no defaults: a zero-initialised frame is refused by name.
// The lights: a LightList or an array, not both (refused by name); neither = no light (a black output, no ray).
struct ManyLightFrame {
  GBufferDesc gbuffer{};  // the engine's G-buffer, its images in their declared layouts
  TlasInfo tlas{};        // from recordTlasBuild() earlier in submission order
  // A LightList recorded this frame for the same TLAS space (refused with a named error otherwise): shared with
  // reflection hits and primary shading, uploaded once.
  const LightList* lightList = nullptr;
  // Or the lights themselves: record() checks every one (the error names its index and field) and uploads them into
  // a list of the pass's own first, inside the pass's time (copied: the array may change right after the call).
  std::span<const LightSource> lights{};
  ManyLightSettings settings{};
};

// Owned by the pass, sized to the G-buffer, left in SHADER_READ_ONLY_OPTIMAL after record(), readable by
// fragment, compute and ray tracing shaders.
struct ManyLightOutputs {
  // R16G16B16A16_SFLOAT: rgb = E, a = 1; sky pixels 0. With schedule.convergedTiles also a = -1 (kept) and a = 2
  // (stale).
  VkImage irradiance = VK_NULL_HANDLE;
  VkImageView irradianceView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
};

class ManyLightPass {
 public:
  static Result<std::unique_ptr<ManyLightPass>> create(Context& context, const ManyLightPassDesc& desc = {});
  // Retires its Vulkan objects to the context, without waiting.
  ~ManyLightPass();

  // Records the tile culling and the shadow rays over the frame's lights into `cmd` (first their upload, when
  // given as an array). An empty list makes the output black and traces no ray. On an error (named field) nothing
  // is recorded.
  Status record(VkCommandBuffer cmd, const ManyLightFrame& frame);
  // Creates the output images at width x height now, so that outputs() names them before the first record()
  // (HybridEffects hands out views that stay valid this way); record() at the same size keeps them, at another
  // size it recreates them. Written by the first record().
  Status prepare(uint32_t width, uint32_t height);
  const ManyLightOutputs& outputs() const;
  // GPU time (culling and tracing, and the upload of lights given as an array) and rays of the latest recording
  // whose frame has finished.
  PassStats stats() const;

  struct Impl;

 private:
  explicit ManyLightPass(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
