// The sample forward engine: owns a Vulkan 1.3 instance/device/queue, renders a Scene with
//   shadow map -> [probe capture] -> depth+normal pre-pass -> [SSAO] -> [shadow visibility] -> [pre-pass hook]
//   -> [local shadow maps] -> [local-light irradiance] -> forward PBR lighting -> blended surfaces -> tonemap
// into an offscreen image (read back to the CPU) and optionally presents it to a swapchain.
//
// Materials (scene.h): glTF metallic-roughness with base colour, metallic-roughness, normal, emissive and
// occlusion textures, and the glTF alpha modes and sidedness in every raster pass:
//   * OPAQUE: pre-pass, lighting (depth EQUAL), shadow map (positions only).
//   * MASK: as OPAQUE, with fragments where alpha < alphaCutoff discarded in every pass (the shadow map takes
//     an alpha-tested pipeline for them; opaque draws keep the positions-only one).
//   * BLEND: not in the pre-pass, so the depth and normals the hook and the SSAO see are the opaque scene's.
//     After the opaque lighting they are shaded like it and blended into the HDR target (src alpha, one minus
//     src alpha), depth test LESS against the pre-pass depth without writes, sorted back to front by the
//     distance from the eye to each instance's bounding-box centre (a double-sided one draws its back faces
//     first). Lighting: sun with the shadow map when one is drawn (else unshadowed), the sky ambient and the
//     engine's own environment term (probe or constant sky). The LightingInputs describe the opaque surface
//     behind, so blended surfaces ignore all three of them (and the SSAO). In the shadow map a BLEND surface
//     casts with a hashed alpha test: each shadow-map texel is covered with probability alpha (a hash of the
//     texel and the instance, stable from frame to frame), so after PCF it blocks alpha of the light in the
//     mean, like the SDK's stochastic BLEND shadows.
//   * Material::doubleSided false culls back faces in the camera passes (cull mode and front face per draw,
//     the winding flipped for model matrices with a negative determinant); the shadow map never culls.
// Mip-mapped MASK textures are not coverage-corrected (thin cut-outs thin out at a distance), and blended
// surfaces are sorted per instance, not per triangle.
//
// Punctual lights (Scene::lights, KHR_lights_punctual): every frame places them with the animated nodes
// (frameLights()) and writes them into a per-frame storage buffer; the lighting adds all of them (a loop over
// every light per pixel: the engine's limitation for many lights). The strongest LocalLightSettings::
// maxShadowedLights get shadow maps (spot: one perspective view, point: six, directional: one orthographic),
// drawn after the pre-pass hook so that an external LightingInputs::localLightIrradiance can skip them; the
// others are unshadowed. outputLocalLightIrradiance writes the engine's own E for readback.
//
// Animated scenes (glTF node animation, skins, morph targets): each frame first evaluates the animation on
// the CPU (FrameParams::time / animations / restPose), then, when the scene has deforming (skinned and/or
// morphed) instances, a compute submission writes each one's deformed vertex buffers and signals a timeline
// semaphore to the frame number; the main submission waits on it. Static scenes skip both.
//
// With FrameParams::externalColor the hook supplies the whole frame's colour instead (pure ray tracing): the
// engine then only clears the pre-pass images, calls the hook with its HDR target and tonemaps what it wrote.
//
// Add-ons (e.g. a ray-tracing adapter) plug in through four small things:
//   * EngineConfig: extra device extensions / feature chain, so they can share the engine's device;
//   * setPrepassHook(): called with the frame's command buffer between the pre-pass and the lighting pass;
//   * LightingInputs: external sun-visibility / AO / reflection / KHR-light irradiance images the lighting samples.
//   * setOverlayHook(): called with the frame's command buffer after the tonemap pass, to draw a UI on top.
//
// Thread safety: Engine is not thread-safe; call it from one thread at a time (the hook runs on the thread
// that called renderFrame()). The spans it returns stay valid until the next loadScene() / destruction.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

#include <glm/glm.hpp>

#include "sample_engine/animation.h"
#include "sample_engine/image_io.h"
#include "sample_engine/result.h"
#include "sample_engine/scene.h"

namespace sample_engine {

inline constexpr uint32_t kFramesInFlight = 2;

// A zeroed Vulkan struct with its sType set (avoids -Wmissing-field-initializers in including code).
template <typename T>
T vkStruct(VkStructureType type) {
  T value{};
  value.sType = type;
  return value;
}

struct EngineConfig {
  // Enables VK_LAYER_KHRONOS_validation plus a debug messenger that counts (and prints) errors.
  bool enableValidation = false;
  // Gives vertex/index buffers SHADER_DEVICE_ADDRESS + STORAGE usage (plus
  // ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY when VK_KHR_acceleration_structure is among the enabled device
  // extensions) and reports their addresses in GpuMesh. The bufferDeviceAddress feature itself is always
  // enabled (Vulkan 1.3 requires it; the deformation pass reads and writes vertex buffers through it).
  bool enableRayTracingInputs = true;
  // Adds VK_KHR_swapchain to the device; needed by attachSurface().
  bool enableSwapchain = false;
  // Extra instance extensions (e.g. from Window::requiredInstanceExtensions()).
  std::vector<std::string> instanceExtensions;
  // Extra device extensions an add-on needs; devices lacking one are not chosen.
  std::vector<std::string> deviceExtensions;
  // Device extensions an add-on uses where present: enabled when the chosen device has them, never a reason to
  // pass a device over (Engine::enabledDeviceExtensions() tells). `features` (optional, pNext null): that
  // extension's feature struct, filled with what the device supports and chained only when the extension is
  // enabled; it must stay alive during Engine::create().
  struct OptionalDeviceExtension {
    std::string name;
    void* features = nullptr;
  };
  std::vector<OptionalDeviceExtension> optionalDeviceExtensions;
  // Extra feature structs appended to the engine's VkPhysicalDeviceFeatures2 chain at device creation
  // (e.g. acceleration-structure / ray-query features). It must not contain VkPhysicalDeviceFeatures2 or
  // VkPhysicalDeviceVulkan11/12/13Features: set the core features you need in the fields below, which are
  // OR-ed into the engine's own. The chain must stay alive during Engine::create().
  const void* deviceFeaturesPNext = nullptr;
  VkPhysicalDeviceFeatures extraFeatures10{};
  VkPhysicalDeviceVulkan11Features extraFeatures11 = vkStruct<VkPhysicalDeviceVulkan11Features>(
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES);
  VkPhysicalDeviceVulkan12Features extraFeatures12 = vkStruct<VkPhysicalDeviceVulkan12Features>(
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES);
  VkPhysicalDeviceVulkan13Features extraFeatures13 = vkStruct<VkPhysicalDeviceVulkan13Features>(
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES);
  // Also create one queue of a compute-capable family without graphics (when the device has one; lavapipe
  // does not) for add-ons, e.g. asynchronous BLAS builds: see Engine::asyncComputeQueue(). The engine never
  // submits to it; deformed vertex buffers and the index buffers of deforming meshes are then shared
  // (CONCURRENT) between both families.
  bool requestAsyncComputeQueue = false;
  // Substring of the device name to pick. Empty: environment variable SAMPLE_ENGINE_DEVICE, else the
  // first discrete GPU, else the first device that works.
  std::string deviceNameFilter;
  std::string applicationName = "raybridge-sample-engine";
  // Test hooks (failure injection): the functions the frame loop submits with (each frame's and its deformation's
  // vkQueueSubmit2) and waits for a frame slot's fence with. nullptr = the loader's vkQueueSubmit2 and
  // vkWaitForFences. A replacement forwards to those, or returns an error such as VK_ERROR_DEVICE_LOST to see how
  // the engine reports it: renderFrame() and waitIdle() return the error, and after a lost device every later call
  // fails at once saying so; the engine can still be destroyed.
  PFN_vkQueueSubmit2 queueSubmit2 = nullptr;
  PFN_vkWaitForFences waitForFences = nullptr;
};

// Limits of ShadowSettings (see there).
inline constexpr uint32_t kMinShadowMapSize = 1024;
inline constexpr uint32_t kMaxShadowMapSize = 8192;
inline constexpr uint32_t kMaxShadowPcfKernel = 9;

// Shadow-map settings; changing the size (or enabling/disabling the map) between frames recreates the map,
// waiting for the GPU first. Engine::lastShadowMapStats() reports what a frame actually used.
struct ShadowSettings {
  // false: no shadow map at all: no shadow-map pass is recorded, the map's memory is released (a 1x1
  // placeholder stays bound) and the sun is unshadowed, except where LightingInputs::sunVisibility is given.
  // The reflection probe and the shadow-visibility output then see an unshadowed sun too.
  bool enabled = true;
  uint32_t mapSize = 2048;  // texels per side, clamped to [kMinShadowMapSize, kMaxShadowMapSize]
  // PCF taps per axis, clamped to [1, kMaxShadowPcfKernel]; 0 = 1 (a single tap). Each tap is a 2x2
  // hardware-filtered depth compare; the n x n taps sit one texel apart at offsets -(n-1)/2 .. +(n-1)/2
  // texels around the lookup, so an even kernel (e.g. 4 or 8) is centred too, its taps at half-texel
  // offsets. The filtered penumbra is about n texels wide.
  uint32_t pcfKernelSize = 3;
  float depthBiasConstant = 1.5f;
  float depthBiasSlope = 2.0f;
  // Lookup offset along the geometric normal, in shadow-map texels; the engine adds (kernel - 1) / 2 texels
  // so that the outer taps of a wide kernel do not shadow the receiver's own slope.
  float normalOffset = 1.5f;
};

// The shadow map a rendered frame actually used: ShadowSettings after clamping (Engine::lastShadowMapStats()).
struct ShadowMapStats {
  bool enabled = false;      // false: no shadow map (ShadowSettings::enabled off, or no frame rendered yet)
  uint32_t mapSize = 0;      // texels per side, in [kMinShadowMapSize, kMaxShadowMapSize]; 0 when not enabled
  uint32_t pcfKernel = 0;    // PCF taps per axis, in [1, kMaxShadowPcfKernel]; 0 when not enabled
  uint64_t frameNumber = 0;  // Engine::frameNumber() of that frame; 0 before the first frame
};

// One punctual light as this frame places it (node animation applied), world space.
// Plain data: not thread-safe.
struct FrameLight {
  PunctualLight::Type type = PunctualLight::Type::Point;
  uint32_t light = 0;                      // Scene::lights index
  glm::dvec3 position{0.0};                // world (double: large worlds)
  glm::vec3 direction{0.0f, 0.0f, -1.0f};  // the way the light travels = node's -Z in world, normalized
  glm::vec3 color{1.0f};
  float intensity = 1.0f;
  float range = 0.0f;                                                        // 0 = unlimited
  float innerConeAngle = 0.0f, outerConeAngle = kDefaultSpotOuterConeAngle;  // radians
};

// Raster shadows for local (KHR) lights: maps for the strongest ones, in a 2D array of 6 layers per shadowed light
// (a spot with an outer cone up to pi/3 uses one perspective view over its cone, a wider spot or a point six
// 90-degree views, a directional light one orthographic view over the scene's bounding sphere like the sun's).
// "Strongest" = the largest unshadowed irradiance estimate at the eye: luminance(color) * intensity, divided
// for point and spot lights by the squared distance to the eye (at least 1), ignoring the cone, the range and
// any cosine; ties keep Scene::lights order; black or zero-intensity lights never get a map. The maps are drawn
// after the pre-pass hook and skipped when it sets LightingInputs::localLightIrradiance (unless
// FrameParams::outputLocalLightIrradiance wants the engine's own E). Changing the count or size recreates them,
// waiting for the GPU first.
inline constexpr uint32_t kMaxShadowedLocalLights = 8;
inline constexpr uint32_t kDefaultMaxShadowedLocalLights = 4;
inline constexpr uint32_t kDefaultLocalShadowMapSize = 512;
inline constexpr uint32_t kMinLocalShadowMapSize = 64;  // mapSize is clamped to [min, max]
inline constexpr uint32_t kMaxLocalShadowMapSize = 4096;
// The KHR lights (Scene::lights) of a frame. Every light is drawn; the `maxShadowedLights` strongest get shadow
// maps, the others are unshadowed. Plain data: not thread-safe.
struct LocalLightSettings {
  bool enabled = true;  // false: KHR lights are not drawn at all by the engine (sun only)
  // Strongest lights that get shadow maps, clamped to kMaxShadowedLocalLights; 0 = none.
  uint32_t maxShadowedLights = kDefaultMaxShadowedLocalLights;
  // Texels per side of each map (per cube face for points), clamped to [kMinLocalShadowMapSize,
  // kMaxLocalShadowMapSize].
  uint32_t mapSize = kDefaultLocalShadowMapSize;
  uint32_t pcfKernelSize = 3;                                                  // as ShadowSettings::pcfKernelSize
  float depthBiasConstant = 1.5f, depthBiasSlope = 2.0f, normalOffset = 1.5f;  // as ShadowSettings
};
// What a rendered frame did with the KHR lights (Engine::lastLocalShadowStats()). Plain data: not thread-safe.
struct LocalShadowStats {
  uint32_t lights = 0;          // lights drawn (0 when LocalLightSettings::enabled is off)
  uint32_t shadowedLights = 0;  // of them, the ones with a shadow map this frame
  uint32_t shadowViews = 0;     // shadow-map views drawn (1 per spot / directional, 6 per point)
  uint64_t frameNumber = 0;     // Engine::frameNumber() of that frame; 0 before the first frame
};

// The engine's own screen-space ambient occlusion: GTAO (Jimenez et al. 2016) in compute. Per pixel, slices
// through the view vector; in each, the pre-pass depth is searched on both sides for the highest horizon within
// `radius`, and the cosine-weighted visible arc is integrated analytically against the pre-pass geometric
// normal projected into the slice. The result (normalised so that an unoccluded surface is exactly 1) goes
// into an R16F image (1 = open). The lighting pass multiplies its ambient terms by it unless
// LightingInputs::ambientOcclusion is set; it is computed whenever enabled, so readbackSsao() also works next
// to an external AO input (e.g. to compare the two).
inline constexpr uint32_t kDefaultSsaoKernelSize = 16;
inline constexpr uint32_t kMaxSsaoKernelSize = 64;
inline constexpr float kDefaultSsaoRadius = 0.5f;
inline constexpr float kDefaultSsaoBias = 0.025f;
struct SsaoSettings {
  bool enabled = false;
  // Depth taps per pixel, clamped to [1, kMaxSsaoKernelSize] (0 = 1): floor(sqrt(kernelSize / 2)) slices (at
  // least 1), each searched with kernelSize / (2 * slices) taps per side (at least 1); 16 = 2 slices x 4 taps.
  uint32_t kernelSize = kDefaultSsaoKernelSize;
  // World units: occluders farther away do not count (faded out over its last 20%); the search also stops a
  // quarter of the render height from the pixel on screen. 0 = nothing occludes.
  float radius = kDefaultSsaoRadius;
  // World units: the horizon search starts this far above the surface along its normal, so that depth
  // quantisation on flat ground does not occlude; 0 = none, negative = 0.
  float bias = kDefaultSsaoBias;
  float power = 1.0f;  // ao = visibility^power; 0 = no darkening (ao = 1)
  bool blur = true;    // 4x4 depth/plane-aware blur that removes the 4x4 slice-rotation pattern
};

// A static reflection probe: a small cubemap captured from one point with the engine's forward shading (sun,
// shadow map, constant-sky ambient; background = skyColor * ambientIntensity, the radiance the constant-sky
// fallback uses, so a probe that sees only sky changes nothing). When enabled the lighting pass samples it
// along the reflection vector (mip chosen by roughness) instead of the constant sky; an external
// LightingInputs::reflection replaces it where its alpha (coverage) is 1. Captured on the first enabled frame
// and recaptured only when the scene, the probe settings, the sun, the sky or the shadow settings change.
struct ReflectionProbeSettings {
  bool enabled = false;
  uint32_t resolution = 64;           // per face, clamped to [8, 512]
  std::optional<glm::vec3> position;  // default: scene bounds centre, raised to heightAboveGround
  float heightAboveGround = 1.5f;     // default position: y >= bounds.min.y + this (world units)
};

// External images the lighting pass samples instead of its own terms. Each must be a 2D view that stays
// valid until the frame completes, in VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL when the lighting pass
// runs, and covering the whole viewport (any resolution: sampled bilinearly at the pixel's UV).
// They describe the opaque surface of the pre-pass at each pixel, so they light OPAQUE and MASK surfaces only:
// a BLEND surface in front of it takes the shadow map (unshadowed without one), no AO image and the engine's
// own environment term instead.
struct LightingInputs {
  // R channel, 1 = lit, 0 = shadowed (R8_UNORM / R16_SFLOAT / R32_SFLOAT...). Replaces the shadow map.
  VkImageView sunVisibility = VK_NULL_HANDLE;
  // R channel, 1 = unoccluded. Multiplies the ambient (sky) terms.
  VkImageView ambientOcclusion = VK_NULL_HANDLE;
  // RGB = linear radiance arriving along the mirror direction, A = coverage (RGBA16F). The specular ambient
  // term becomes mix(engine's own, rgb, a): 1 = use the external radiance, 0 = keep the engine's own term
  // (constant sky * AO, or the reflection probe when enabled), e.g. where a ray-traced pass traced nothing.
  // The engine weights the result by its Fresnel/roughness environment BRDF.
  VkImageView reflection = VK_NULL_HANDLE;
  // RGBA16F, rgb = shadowed diffuse irradiance E from all KHR lights (no BRDF, no albedo; units as
  // PunctualLight). When set, the engine's local-light diffuse becomes albedo*(1-metallic)/pi * E (as its sun
  // diffuse convention), its local shadow maps are not drawn, and its local-light specular is scaled by
  // the ratio lum(E) / lum(E_unshadowed) clamped to [0,1] (ratio estimator, Heitz et al. 2018).
  VkImageView localLightIrradiance = VK_NULL_HANDLE;
};

// Everything a frame needs besides the scene.
struct FrameParams {
  Camera camera;
  Sun sun;
  glm::vec3 skyColor{0.45f, 0.62f, 0.9f};  // linear; background and constant ambient light
  float ambientIntensity = 0.4f;
  float exposure = 1.0f;
  ShadowSettings shadow;
  LightingInputs lightingInputs;  // the pre-pass hook may change these for the frame
  SsaoSettings ssao;
  ReflectionProbeSettings reflectionProbe;
  LocalLightSettings localLights;
  // Also writes the engine's own (shadow-mapped) KHR-light irradiance E to an RGBA16F image for
  // readbackLocalLightIrradiance(): a fullscreen pass after the local shadow maps (so after the hook), from the
  // pre-pass depth, with the cosine of the SHADING normal (normalRoughness) and the shadow lookup offset along
  // the geometric normal; background 0. Draws the local shadow maps even under an external irradiance.
  bool outputLocalLightIrradiance = false;
  // Also writes the shadow-map sun visibility the lighting uses (PCF, and 0 where the shading normal faces
  // away from the sun; 1 on background) into an R16F image for readbackShadowVisibility().
  bool outputShadowVisibility = false;
  // The pre-pass hook supplies the frame's colour (e.g. a ray tracer shading primary rays): the engine records no
  // shadow map, probe capture, pre-pass draws (depth and normals are only cleared: far plane, 0), SSAO, shadow
  // visibility, local shadow maps or lighting (blended surfaces included), so their timings are about 0. Before
  // the hook the HDR target is cleared to skyColor and handed over as PrepassHookInfo::hdrColor; the tonemap,
  // readbackHdr() and readbackLdr() show what the hook wrote there. renderFrame fails when an output above is also
  // requested (outputLocalLightIrradiance, outputShadowVisibility): the engine shades nothing to output.
  bool externalColor = false;
  // Animation time in seconds; must be finite and >= 0 (renderFrame fails naming the value otherwise).
  double time = 0.0;
  // The animations that play this frame, each at time + timeOffset, looping over its own duration, applied in
  // order (later channels override earlier ones). Empty (default) = the scene's first animation, if any, at
  // `time`. An index beyond Scene::animations fails renderFrame (the message lists the scene's animations).
  std::vector<AnimationPlayback> animations;
  bool restPose = false;  // true = no animation plays: nodes keep their rest transforms and weights
};

// A deforming (skinned and/or morphed) instance of the loaded scene and its own deformed vertex buffers,
// rewritten by every frame's deformation submission. Fixed from loadScene() on. Read-only for add-ons.
struct DeformedInstance {
  uint32_t instance = 0;  // index into Scene::instances
  uint32_t mesh = 0;      // index into Scene::meshes / Engine::meshes(): the bind pose, topology (indices) and material
  // Deformed positions: R32G32B32_SFLOAT, stride 12, vertexCount entries, in the instance's local space
  // (skinning matrices are inverse(node world) * joint world * inverse bind matrix), so the instance's world
  // transform (Engine::instanceTransforms()) still places it. Usage STORAGE | VERTEX | SHADER_DEVICE_ADDRESS
  // | TRANSFER_SRC | TRANSFER_DST (+ ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY when
  // VK_KHR_acceleration_structure is enabled); VK_SHARING_MODE_CONCURRENT over queueFamily() and
  // asyncComputeQueueFamily() when an async compute queue exists, else EXCLUSIVE.
  VkBuffer positionBuffer = VK_NULL_HANDLE;
  VkDeviceAddress positionAddress = 0;
  // Deformed attributes, interleaved {vec3 normal; vec2 uv; vec4 tangent}, stride 36, like GpuMesh.
  VkBuffer attributeBuffer = VK_NULL_HANDLE;
  VkDeviceAddress attributeAddress = 0;
  uint32_t vertexCount = 0;
  // The box of the pose the latest deformation wrote, in the positions' (instance-local) space: each joint's
  // bind-pose box of the vertices it moves under its joint matrix, widened by the morph targets' reach at the frame's
  // weights (conservative: every deformed vertex lies inside). What a culling pass tests; renderFrame() updates it
  // before the pre-pass hook runs.
  glm::vec3 boundsMin{0.0f}, boundsMax{0.0f};
};

// One image of the pre-pass, as the hook receives it.
struct PassImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkImageLayout layout = VK_IMAGE_LAYOUT_UNDEFINED;  // layout it is in when the hook runs; keep it so
};

struct PrepassHookInfo {
  VkCommandBuffer commandBuffer = VK_NULL_HANDLE;  // recording, outside any rendering scope
  uint32_t frameIndex = 0;                         // frame in flight, 0..kFramesInFlight-1
  uint64_t frameNumber = 0;                        // increments every rendered frame
  VkExtent2D extent{};                             // viewport = size of every pre-pass image
  // The pre-pass images hold OPAQUE and MASK surfaces only (MASK cut-outs show what is behind); BLEND ones
  // are drawn after the lighting pass and never appear here.
  // D32_SFLOAT, standard depth (1.0 = far plane / background), DEPTH_READ_ONLY_OPTIMAL.
  PassImage depth;
  // RGBA16F: xyz = shading normal (world space, normal-mapped, facing the camera), w = perceptual
  // roughness; (0,0,0,0) for background. SHADER_READ_ONLY_OPTIMAL.
  PassImage normalRoughness;
  // RGBA16F: xyz = geometric (triangle) normal in world space, facing the camera, w = metallic;
  // (0,0,0,0) for background. SHADER_READ_ONLY_OPTIMAL.
  PassImage geometricNormal;
  // RG16F: screen-space motion in pixels, this frame's position of the surface point minus last rendered frame's
  // (x right, y down; the camera, instance transforms and skinned / morphed deformation together); (0,0) for
  // background and on the first frame after loadScene(); 32768 where the point was behind last frame's camera.
  // SHADER_READ_ONLY_OPTIMAL.
  PassImage motionVectors;
  bool reversedZ = false;
  // Camera-relative, as the engine rasterizes (precision far from the origin): `view` is rotation only, so
  // viewProj maps world position - cameraPosition to clip space. proj: Vulkan clip space, Y flipped, depth [0,1].
  glm::mat4 view{1.0f}, proj{1.0f}, viewProj{1.0f};
  glm::mat4 invView{1.0f}, invProj{1.0f}, invViewProj{1.0f};
  glm::vec3 cameraPosition{0.0f};            // world-space eye (FrameParams::camera.eye)
  glm::dvec3 cameraPositionD{0.0};           // the same in double: the origin of the camera-relative raster
  glm::vec3 sunDirection{0.0f, 1.0f, 0.0f};  // towards the sun, normalized
  // The frame's lighting (FrameParams): sun colour * intensity, sky colour and ambient intensity.
  glm::vec3 sunRadiance{0.0f};
  glm::vec3 skyColor{0.0f};
  float ambientIntensity = 0.0f;
  // This frame's world transform per Scene::instances entry (node animation applied).
  std::span<const glm::mat4> instanceTransforms;
  // This frame's lights, Scene::lights order (empty if none or LocalLightSettings::enabled is off). The local
  // shadow maps are drawn after the hook.
  std::span<const FrameLight> lights;
  // The deforming instances; this frame's deformation submission rewrites their buffers. Empty for a
  // scene without skinned or morphed instances.
  std::span<const DeformedInstance> deformedInstances;
  // Timeline semaphore the deformation submission signals; VK_NULL_HANDLE when the scene has no deforming
  // instance. It reaches deformValue (= frameNumber) once this frame's deformed buffers are written. The
  // main submission already waits for it (ALL_COMMANDS), so commands recorded in commandBuffer see them.
  VkSemaphore deformSemaphore = VK_NULL_HANDLE;
  uint64_t deformValue = 0;
  // FrameParams::externalColor only (else all null): the frame's HDR target, R16G16B16A16_SFLOAT, `extent` pixels,
  // cleared to skyColor, in VK_IMAGE_LAYOUT_GENERAL, usable as a storage image and a transfer destination. The hook
  // writes the frame's linear colour into it and leaves it in GENERAL; the tonemap then reads it.
  PassImage hdrColor;
  // Waits to add to this frame's main submission (e.g. an async BLAS build on another queue). Never null.
  std::vector<VkSemaphoreSubmitInfo>* submitWaits = nullptr;
  // Waits the engine's NEXT deformation submission performs before it overwrites the deformed buffers (e.g.
  // another queue still reads them). nullptr when the scene has no deforming instance. Dropped by loadScene()
  // and waitIdle() (all of them are met then), so an add-on may destroy their semaphores after waitIdle().
  std::vector<VkSemaphoreSubmitInfo>* deformWaits = nullptr;
};

// Called once per frame after the pre-pass, before the lighting pass. May record commands into
// info.commandBuffer (it must leave the pre-pass images in the layouts given) and may set `inputs`.
// Images it writes and passes in `inputs` must be in SHADER_READ_ONLY_OPTIMAL at the end of the hook;
// the engine then adds a full memory barrier (all commands -> fragment shader reads).
using PrepassHook = std::function<void(const PrepassHookInfo& info, LightingInputs& inputs)>;

// --- Overlay hook ------------------------------------------------------------------------------------------
// Lets an add-on (a debug UI such as Dear ImGui, a frame counter) draw on top of the finished, tonemapped frame.
// Called once per frame after the tonemap pass, before the frame is blitted to the swapchain, so what it draws
// is presented and also appears in readbackLdr(); headless frames call it too. Everything a renderer backend
// needs to initialise itself lazily on the first call is in the info.
struct OverlayHookInfo {
  VkCommandBuffer commandBuffer = VK_NULL_HANDLE;  // recording, outside any render pass or rendering scope
  uint32_t frameIndex = 0;                         // frame in flight, 0..framesInFlight-1
  // Frames in flight (kFramesInFlight, >= 2): per-frame data the add-on writes must be ring-buffered over at
  // least this many. When the hook runs for frame N, every frame up to N - framesInFlight has finished on the GPU.
  uint32_t framesInFlight = kFramesInFlight;
  uint64_t frameNumber = 0;  // increments every rendered frame (Engine::frameNumber() once renderFrame returns)
  // The tonemapped colour target, extent x extent: R8G8B8A8_SRGB (blending is linear, so colours authored in
  // sRGB, like ImGui's, look lighter unless linearised), COLOR_ATTACHMENT_OPTIMAL with the tonemap's writes
  // visible. Use it only as a colour attachment and leave it in that layout; the engine then makes the writes
  // visible to its blit / readback.
  PassImage target;
  VkExtent2D extent{};
  // A render pass whose single subpass has target's format as its only colour attachment (1 sample,
  // LOAD_OP_LOAD, STORE_OP_STORE, initial and final layout COLOR_ATTACHMENT_OPTIMAL), for pipelines built
  // against a VkRenderPass; the same handle every frame, valid until the engine is destroyed. framebuffer is
  // target in that pass, valid during this call only (it changes on resize). Dynamic-rendering pipelines use
  // vkCmdBeginRendering with target.view / target.format instead.
  VkRenderPass renderPass = VK_NULL_HANDLE;
  VkFramebuffer framebuffer = VK_NULL_HANDLE;
  uint32_t swapchainImageCount = 0;  // images of the swapchain the frame goes to; 0 when headless
  // The engine's Vulkan objects (as Engine's accessors), so a backend can initialise on the first call.
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physicalDevice = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;  // the engine submits commandBuffer here; do not submit to it from the hook
  uint32_t queueFamily = 0;
  PFN_vkGetInstanceProcAddr getInstanceProcAddr = nullptr;
  uint32_t apiVersion = 0;
};

// Records the overlay's draws into info.commandBuffer (see OverlayHookInfo). Runs on the thread that called
// renderFrame(), after the pre-pass hook of the same frame. Costs nothing when no hook is set.
using OverlayHook = std::function<void(const OverlayHookInfo& info)>;

struct PassTimings {
  double shadowMs = 0.0;
  double probeMs = 0.0;  // reflection-probe capture (0 on frames without a capture)
  double prepassMs = 0.0;
  double ssaoMs = 0.0;              // SSAO (GTAO) + blur, both compute (0 when disabled)
  double shadowVisibilityMs = 0.0;  // shadow-visibility output (0 unless requested)
  double hookMs = 0.0;              // whatever the hook recorded
  double lightingMs = 0.0;          // opaque lighting and the blended surfaces after it
  double tonemapMs = 0.0;
  double deformMs = 0.0;           // the deformation submission (skinning / morphing); 0 when nothing deforms
  double localShadowMs = 0.0;      // local shadow maps (0 when none drawn)
  double localIrradianceMs = 0.0;  // outputLocalLightIrradiance pass
  bool probeCaptured = false;      // this frame captured the reflection probe
  bool valid = false;              // false until a frame with timestamps has completed
  uint64_t frameNumber = 0;        // Engine::frameNumber() of the frame these timings belong to
};

// A mesh as uploaded. Positions are R32G32B32_SFLOAT, tightly packed (stride 12) in their own buffer.
// Attributes are interleaved {vec3 normal; vec2 uv; vec4 tangent} with stride 36 (offsets 0, 12, 20).
// Indices are always uint32 (VK_INDEX_TYPE_UINT32), or absent (VK_INDEX_TYPE_NONE_KHR, indexCount 0).
// Device addresses are 0 unless ray-tracing inputs are enabled.
struct GpuMesh {
  VkBuffer positionBuffer = VK_NULL_HANDLE;
  VkDeviceAddress positionAddress = 0;
  VkFormat positionFormat = VK_FORMAT_R32G32B32_SFLOAT;
  uint32_t positionStride = 12;
  VkBuffer attributeBuffer = VK_NULL_HANDLE;
  VkDeviceAddress attributeAddress = 0;
  uint32_t attributeStride = 36;
  VkBuffer indexBuffer = VK_NULL_HANDLE;
  VkDeviceAddress indexAddress = 0;
  VkIndexType indexType = VK_INDEX_TYPE_NONE_KHR;
  uint32_t vertexCount = 0;
  uint32_t indexCount = 0;
  uint32_t material = 0;
  const MeshData* cpu = nullptr;  // CPU copy (finalized), owned by the engine
};

// A scene texture as uploaded, at its Scene::textures index: an RGBA8 image with a mip chain (one level when
// the device cannot blit RGBA8), in VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL from loadScene() until the next
// loadScene() or the engine's destruction. Read-only for add-ons: sample it, never write or transition it.
// Two 2D views over all mips; pick by the texture's use:
//   srgbView  (R8G8B8A8_SRGB):  sampling decodes sRGB to linear. Base colour and emissive textures.
//   unormView (R8G8B8A8_UNORM): raw values. Metallic-roughness (G = roughness, B = metallic), normal maps.
// All handles are VK_NULL_HANDLE for a texture without texels (empty TextureData::rgba8); materials using
// it sample the engine's 1x1 defaults instead.
struct GpuTexture {
  VkImage image = VK_NULL_HANDLE;
  VkImageView srgbView = VK_NULL_HANDLE;
  VkImageView unormView = VK_NULL_HANDLE;
  uint32_t width = 0, height = 0, mipLevels = 0;
};

struct DeviceInfo {
  std::string name;
  uint32_t apiVersion = 0;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  bool bufferDeviceAddress = false;  // scene buffers expose device addresses (EngineConfig::enableRayTracingInputs)
};

class Engine {
 public:
  static Result<std::unique_ptr<Engine>> create(const EngineConfig& config);
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // --- Vulkan objects, for add-ons sharing the device ---
  VkInstance instance() const;
  VkPhysicalDevice physicalDevice() const;
  VkDevice device() const;
  VkQueue queue() const;  // the single graphics+compute queue the engine submits to
  uint32_t queueFamily() const;
  // The async compute queue (EngineConfig::requestAsyncComputeQueue): VK_NULL_HANDLE when not requested or
  // the device has no compute family without graphics. The engine never uses it; its owner synchronises it.
  VkQueue asyncComputeQueue() const;
  uint32_t asyncComputeQueueFamily() const;  // UINT32_MAX when there is none
  PFN_vkGetInstanceProcAddr getInstanceProcAddr() const;
  uint32_t apiVersion() const;  // the instance/device API version the engine targets (1.3)
  const DeviceInfo& deviceInfo() const;
  const std::vector<std::string>& enabledDeviceExtensions() const;
  uint32_t validationErrorCount() const;  // errors seen by the debug messenger (0 without validation)
  uint32_t validationWarningCount() const;

  // --- Scene ---
  // Copies, finalizes and uploads the scene, replacing the previous one (waits for the GPU first).
  Status loadScene(const Scene& scene);
  const Scene& scene() const;                    // finalized CPU copy
  std::span<const GpuMesh> meshes() const;       // parallel to scene().meshes
  std::span<const GpuTexture> textures() const;  // parallel to scene().textures, see GpuTexture
  Bounds sceneBounds() const;                    // rest pose
  // The deforming (skinned and/or morphed) instances of the loaded scene, in instance order, fixed from
  // loadScene() on (empty for a static scene).
  std::span<const DeformedInstance> deformedInstances() const;
  // World transform of every Scene::instances entry for the last rendered frame (rest pose before the first).
  std::span<const glm::mat4> instanceTransforms() const;
  // Deformed positions of deformedInstances()[deformedIndex] as the last rendered frame wrote them (waits for
  // it); before the first frame, the bind pose. Fails naming the index when it is out of range.
  Result<std::vector<glm::vec3>> readbackDeformedPositions(uint32_t deformedIndex);

  // --- Targets ---
  // Size of the offscreen render targets (headless). With a swapchain the size follows the swapchain.
  Status setRenderSize(uint32_t width, uint32_t height);
  VkExtent2D renderSize() const;
  // Takes ownership of the surface (created on this engine's instance) and creates a swapchain; from then
  // on renderFrame() also presents. Requires EngineConfig::enableSwapchain.
  Status attachSurface(VkSurfaceKHR surface, uint32_t width, uint32_t height);
  Status resizeSwapchain(uint32_t width, uint32_t height);

  // --- Frame ---
  void setPrepassHook(PrepassHook hook);
  // Replaces the overlay hook; an empty function removes it. Its GPU time is not part of PassTimings.
  void setOverlayHook(OverlayHook hook);
  // Records and submits one frame (and presents when a swapchain is attached). Does not wait for it.
  Status renderFrame(const FrameParams& params);
  // Waits until the GPU is idle; afterwards lastTimings() covers the last submitted frame.
  Status waitIdle();
  PassTimings lastTimings() const;
  // The shadow map the last submitted frame used (known at submission, no wait).
  ShadowMapStats lastShadowMapStats() const;
  uint64_t frameNumber() const;

  // Read the last rendered frame back (waits for it): tonemapped sRGB RGBA8, and linear HDR.
  Result<ImageRGBA8> readbackLdr();
  Result<ImageRGBA32F> readbackHdr();
  // The last frame's effect images (waits for it), row-major renderSize() floats, top row first. Fail when
  // that frame did not produce them (FrameParams::outputShadowVisibility / SsaoSettings::enabled).
  Result<std::vector<float>> readbackShadowVisibility();  // 1 = lit, 0 = shadowed
  Result<std::vector<float>> readbackSsao();              // 1 = open (blurred when SsaoSettings::blur)
  // The last frame's engine KHR-light irradiance E (rgb, a = 1), row-major renderSize(), top row first (waits
  // for it). Fails naming FrameParams::outputLocalLightIrradiance when that frame did not produce it.
  Result<std::vector<glm::vec4>> readbackLocalLightIrradiance();
  // The last frame's pre-pass motion vectors (PrepassHookInfo::motionVectors: pixels, this frame - last frame),
  // row-major renderSize(), top row first (waits for it). Fails when that frame drew no pre-pass
  // (FrameParams::externalColor).
  Result<std::vector<glm::vec2>> readbackMotionVectors();

  // --- KHR lights ---
  // The last rendered frame's lights (rest pose before the first), Scene::lights order; empty after a frame
  // with LocalLightSettings::enabled off.
  std::span<const FrameLight> frameLights() const;
  LocalShadowStats lastLocalShadowStats() const;  // known at submission, no wait

  struct Impl;

 private:
  explicit Engine(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace sample_engine
