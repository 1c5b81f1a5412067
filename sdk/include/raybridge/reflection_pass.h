// Ray-traced mirror and glossy reflections on the engine's G-buffer. Pixels whose roughness is under a
// threshold trace one ray (or more) along the mirror direction (glossy: a GGX lobe sampled by visible
// normals); all others trace nothing. Where a ray hits, the surface is shaded with its material (base colour
// factor and texture, metallic-roughness factor and texture, emissive) lit by the sun, with a shadow ray, and
// the sky's ambient light; a ray that escapes returns the sky colour. Output: the radiance arriving along the
// reflected direction (not yet weighted by the surface's Fresnel term, which the engine's shading applies).
//
// Needs: roughness in the G-buffer (GBufferDesc::roughnessInNormalW or roughnessMetalness), a TLAS built
// with TlasBuildOptions::writeShadingRecords, Instance::material set, and the engine's materials and
// textures: a MaterialTable shared with the other passes (ReflectionSettings::materials), or the pass's own
// table given to setMaterials(). Reflection rays and the shadow rays from their hits alpha-test non-opaque
// geometry with the same table (material_table.h).
//
// Half resolution (ReflectionSettings::schedule.halfResolution): one ray generation invocation per 2x2 block of the
// G-buffer traces for one pixel of its block (the same corner in every block, a different one each frame: every pixel
// within 4 frames, so a temporal denoiser sees them all) into an internal R16G16B16A16_SFLOAT image of ceil(w/2) x
// ceil(h/2) (2 bytes per pixel, MemoryCategory::PassImages, held only while the setting is on). A compute pass then
// writes the full-resolution output from it: each pixel weights the covered samples around it bilinearly times
// their depth (distance from the pixel's tangent plane) and normal similarity, so reflections do not bleed across
// silhouettes and creases; a pixel whose sample it is gets that sample exactly. Coverage stays the full-resolution
// pass's: a = 1 on every pixel under the roughness threshold (one with no similar sample takes the most similar
// covered one nearby), 0 on the sky and rougher pixels. The output keeps its format, size and layout. stats() then
// counts the rays actually traced (about a quarter) and its gpuMs covers the trace and the upsample.
//
// Shader execution reordering: on a Context with DeviceInfo::invocationReorder (the engine enabled
// VK_NV_ray_tracing_invocation_reorder, context.h), the pass also builds a second pipeline whose ray generation
// shader traces each ray into a hit object, regroups the threads by the instance hit (misses apart) and only then
// runs the closest-hit or miss shader: hit shading (material lookup, textures, a shadow ray) runs with fewer
// divergent lanes. The rays and the shading are those of the plain pipeline; only the order differs. Elsewhere
// (lavapipe, say) the plain pipeline runs and the setting is ignored: no error, nothing else built.
//
// Converged tiles (ReflectionSettings::schedule.convergedTiles, full resolution): as for soft shadows and AO
// (raybridge/ray_schedule.h), tiles whose denoised reflection history (a DenoiseSignal::Reflection Denoiser) has
// converged trace no ray and hold kept-history marks for that denoiser: (the reprojected history mean, a = -1). A
// refreshed tile whose new rays disagree with its history (beyond the noise the denoiser measured, over the tile or
// in any one pixel) is held, and its pixels get a = 2, which tells the denoiser to drop their stale history. A
// reflection also depends on where it is seen from, which the history cannot follow: a tile is converged only while
// the view of its pixels has turned by less than a quarter of their glossy lobe's width from the views its history
// holds (summed over the frames, a traced frame taking off the share of the history its rays replace, so a slow
// orbit is caught too; turning the camera in place turns nothing; a mirror's lobe is a few thousandths of a radian
// wide). The launch stays one invocation per pixel: those of a
// skipped tile return at once (a list of the tiles left, as the shadow and AO passes trace, cost the reflection
// pass more than it saved where measured: docs/performance.md). PassStats counts the tiles traced, skipped and
// converged, and the reflection rays saved (not counting the shadow rays their hits would have traced). The tile
// state takes 4 bytes per tile (MemoryCategory::PassBuffers), held only while the setting is on.
//
// Sun visibility from the screen (ReflectionFrame::sunVisibility, ReflectionSettings::sunVisibilityMinRoughness): the
// sun's visibility of every surface on screen exists already where shadows were traced this frame for the same sun
// (the ShadowPass's visibility, or its denoised image). A hit of a ray from a pixel at least that rough reads it there
// instead of tracing its sun shadow ray, where the hit projects into the G-buffer and the G-buffer's surface at that
// pixel is the hit's own: the hit lies within kReflectionSunCacheDistanceTolerance of its view distance from that
// surface's tangent plane, the normals agree within kReflectionSunCacheMinNormalCos, and the hit is on the side the
// camera sees. Hits off screen, hidden from the camera or on another surface trace as usual, and so do mirror-like
// pixels (roughness under 0.02: their reflection shows a shadow's edge sharply, and a soft or denoised one is not
// what they would trace). stats().rays counts the rays traced, so the shadow rays read from the screen are the
// difference to a run without it; the image's value is used as it is (a soft shadow's penumbra, the denoiser's
// history), where the traced ray is hard. See docs/performance.md ("Reflections: sun visibility from the shadow
// image") for what it saves and what it changes.
//
// Lifetime: destroying it is safe while frames that recorded it are in flight: its pipeline, output image,
// material table, texture set and measurement objects are handed to the Context's deferred release (see
// context.h) and freed once those frames are done. Destroy it before its Context.
//
// Thread safety: externally synchronised, like the Context it was created from.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>
#include <raybridge/light_list.h>
#include <raybridge/material_table.h>
#include <raybridge/ray_schedule.h>
#include <raybridge/scene_lighting.h>

#include <memory>
#include <span>

namespace rb {

// Defaults of ReflectionSettings (what a zero field means).
inline constexpr float kDefaultReflectionRoughnessThreshold = 0.3f;
inline constexpr uint32_t kDefaultReflectionRays = 1;
inline constexpr uint32_t kDefaultReflectionLightCandidates = 4;  // local lights weighed per hit
// Pixels at least this rough read their hits' sun visibility from ReflectionFrame::sunVisibility (where given): their
// lobe blurs a shadow's edge more than the screen image's softness differs from a traced ray's (docs/performance.md).
inline constexpr float kDefaultReflectionSunCacheRoughness = 0.2f;
// The screen's surface is the hit's own when the hit lies within this fraction of its view distance from the
// surface's tangent plane at the pixel it projects to, and their normals' cosine is at least the second: tight
// enough that a contact (an object resting on a floor) or a crease reads the other surface rarely.
inline constexpr float kReflectionSunCacheDistanceTolerance = 0.01f;
inline constexpr float kReflectionSunCacheMinNormalCos = 0.9f;

// A zero-initialised ReflectionSettings is valid: every zero field means the default constant above.
struct ReflectionSettings {
  float roughnessThreshold = 0.0f;  // 0 = kDefaultReflectionRoughnessThreshold: rougher surfaces trace nothing
  uint32_t raysPerPixel = 0;        // glossy pixels; 0 = kDefaultReflectionRays (noisy: denoise or accumulate)
  SceneLighting lighting{};         // the sun with its shadow ray, what escaping rays return, the sky light on hits
  // The table hits shade with and alpha-test with; nullptr = the pass's own table (setMaterials()).
  const MaterialTable* materials = nullptr;
  // Local lights: hits are also lit by this LightList, recorded earlier this frame for the same TLAS space, one
  // light per hit chosen among lightCandidates in proportion to its unshadowed contribution there, with a shadow
  // ray (unbiased, noisy like glossy rays). nullptr = sun and sky only.
  const LightList* lights = nullptr;
  uint32_t lightCandidates = 0;  // 0 = kDefaultReflectionLightCandidates; at most 64
  // false (default) = trace as usual; true = reorder the hits before shading them (shader execution reordering)
  // where the Context has it (DeviceInfo::invocationReorder), else trace as usual. Same rays and shading either
  // way; only the order the closest-hit shaders run in differs. Opt-in because it did not pay on the one device
  // measured (the pass was slower with it: docs/performance.md); measure it on yours.
  // ReflectionPass::reordered() says what a record did.
  bool invocationReorder = false;
  // Where and how many rays (ray_schedule.h): half resolution (see Half resolution above) and converged tiles
  // (skip the 8x8-pixel tiles whose denoised history has converged and whose view has not turned, see Converged
  // tiles above: their pixels hold kept-history marks, a = -1, which the Reflection Denoiser schedule.history
  // reads; full resolution only). Zero = every pixel traces its rays.
  RaySchedule schedule{};
  // Where the world changed since the last frame, in world space (HybridEffects hands over the reach of every local
  // light that changed as relitBoxes unless ReflectionEffectSettings::disableRelitResets). A reflection shows a change
  // the pixel's own surface does not: the lamp that moved, seen in a mirror. So the rays test them: a pixel whose
  // reflection ray crosses a box of changedBoxes (an object moved into or out of its path), or whose hit's sun ray
  // does (a moved object's shadow seen in the mirror), or whose hit lies in a box of relitBoxes (the reach of a light
  // that moved, switched or changed), writes a = 2: its history is stale, and the Denoiser filtering the output
  // starts it afresh. At most kMaxReflectionChangedBoxes in the two together; each min <= max and finite. Ignored at
  // half resolution (the upsample writes coverage, a = 1). Empty (default) = no test.
  std::span<const ChangedBox> changedBoxes{};
  std::span<const ChangedBox> relitBoxes{};
  // Sun visibility from the screen (see the top): pixels at least this rough read their hits' sun visibility from
  // ReflectionFrame::sunVisibility instead of tracing the shadow ray, where the hit is on screen and the same surface;
  // mirror-like pixels (under 0.02) always trace. 0 = kDefaultReflectionSunCacheRoughness; at most 1. Without
  // ReflectionFrame::sunVisibility every hit traces.
  float sunVisibilityMinRoughness = 0.0f;
};

// Largest ReflectionSettings::changedBoxes plus relitBoxes: the GPU tests every box for every ray (HybridEffects merges
// its boxes to fit).
inline constexpr uint32_t kMaxReflectionChangedBoxes = 256;

// Fixed for the pass's life. Zero-initialised = images created at the first record().
struct ReflectionPassDesc {
  // Create the output images at width x height now (as prepare()), so that outputs() names them and the first
  // record() allocates nothing; 0 x 0 = at the first record(). Both or neither.
  uint32_t width = 0, height = 0;
};

// What one record() traces. The G-buffer and TLAS have no defaults: a zero-initialised frame is refused by name.
struct ReflectionFrame {
  GBufferDesc gbuffer{};  // the engine's G-buffer (with roughness), its images in their declared layouts
  TlasInfo tlas{};        // from recordTlasBuild() earlier in submission order
  ReflectionSettings settings{};
  // Optional: the sun's visibility of the G-buffer's pixels this frame (.r, 1 = lit, 0 = shadowed, read clamped to
  // [0, 1]), traced for the sun of settings.lighting, e.g. ShadowOutputs::visibility or a Denoiser's output of it (not
  // a raw image with kept-history marks: pass the denoised one there). HybridEffects gives it when its shadow effect
  // is on and the reflection G-buffer has the frame's depth buffer. Any float or unorm colour format, the G-buffer's
  // size (width and height, when stated, are checked), in a sampled-read layout (as GBufferImage), written before
  // record() and made visible to ray tracing shaders. Hits read it per settings.sunVisibilityMinRoughness (see the
  // top). VK_NULL_HANDLE (default) = every hit traces its sun ray.
  GBufferImage sunVisibility{};
};

// Owned by the pass, left in SHADER_READ_ONLY_OPTIMAL after record().
struct ReflectionOutputs {
  // R16G16B16A16_SFLOAT: rgb radiance, a = 1 where rays were traced. With schedule.convergedTiles also a = -1 where a
  // converged tile kept its history (rgb is then that history's mean), and a = 2 where a converged tile's refresh
  // found a change (traced; its history is stale, and the denoiser drops it).
  VkImage radiance = VK_NULL_HANDLE;
  VkImageView radianceView = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  uint32_t width = 0, height = 0;
};

class ReflectionPass {
 public:
  static Result<std::unique_ptr<ReflectionPass>> create(Context& context, const ReflectionPassDesc& desc = {});
  // Retires its Vulkan objects to the context, without waiting: the images of outputs() stay valid for
  // the frames already recorded.
  ~ReflectionPass();

  // Fills the pass's own MaterialTable (MaterialTable::setMaterials), used where ReflectionSettings::materials
  // is nullptr. Call when they change; the previous table is released once frames in flight are done with it.
  Status setMaterials(std::span<const Material> materials, std::span<const VkImageView> textures);
  // Records the reflection rays of `frame` into `cmd`. On an error (named field) nothing is recorded.
  Status record(VkCommandBuffer cmd, const ReflectionFrame& frame);
  // Creates the output images at width x height now, so that outputs() names them before the first record()
  // (HybridEffects hands out views that stay valid this way); record() at the same size keeps them, at another
  // size it recreates them. Written by the first record().
  Status prepare(uint32_t width, uint32_t height);
  const ReflectionOutputs& outputs() const;
  PassStats stats() const;
  // Whether the latest record() traced with shader execution reordering (ReflectionSettings::invocationReorder,
  // DeviceInfo::invocationReorder); false before the first record().
  bool reordered() const;

  struct Impl;

 private:
  explicit ReflectionPass(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rb
