// The push constants of every pass (mirrors of shaders/raybridge_pass_constants.glsl), and the code that fills
// the camera and G-buffer part the G-buffer passes share.
#pragma once

#include <raybridge/acceleration_structures.h>
#include <raybridge/ao_pass.h>
#include <raybridge/effects.h>
#include <raybridge/gbuffer.h>

#include <cstddef>
#include <cstdint>
#include <string>

// Bindings, flags and enumerations shared with the GLSL (only #defines).
#include "raybridge_shader_interface.glsl"

namespace rb {

// One push constant struct per pass, each mirroring the struct of the same name in
// shaders/raybridge_pass_constants.glsl field by field (std430: a vec3 is 16-byte aligned and may be followed by
// a scalar, a mat3 is three columns 16 bytes apart). The asserts below hold the offsets written there.
#define RB_ASSERT_OFFSET(type, field, offset) \
  static_assert(offsetof(type, field) == (offset), #type "::" #field " must match raybridge_pass_constants.glsl")

struct GBufferConstants {
  float inverseProjection[16];
  float viewToWorld[3][4];  // columns; .w unused
  float cameraToTlas[3];    // camera position in the TLAS's space
  float depthQuantum;       // one step of the stored depth value; 0 = float depth
  uint32_t size[2];
  uint32_t flags;  // RB_GB_*
  uint32_t frameIndex;
  float wAtDepthOne;   // w of inverse(projection) * (x, y, 1, 1)
  uint32_t resetRays;  // RaySchedule::resetRays, traced where the reactive mask is set (RB_GB_REACTIVE); 0 = none
  uint32_t pad[2];
};
static_assert(sizeof(GBufferConstants) == 160);
RB_ASSERT_OFFSET(GBufferConstants, inverseProjection, 0);
RB_ASSERT_OFFSET(GBufferConstants, viewToWorld, 64);
RB_ASSERT_OFFSET(GBufferConstants, cameraToTlas, 112);
RB_ASSERT_OFFSET(GBufferConstants, depthQuantum, 124);
RB_ASSERT_OFFSET(GBufferConstants, size, 128);
RB_ASSERT_OFFSET(GBufferConstants, flags, 136);
RB_ASSERT_OFFSET(GBufferConstants, frameIndex, 140);
RB_ASSERT_OFFSET(GBufferConstants, wAtDepthOne, 144);
RB_ASSERT_OFFSET(GBufferConstants, resetRays, 148);

struct ShadowConstants {
  GBufferConstants gbuffer;
  float lightDirection[3];  // towards a directional light, unit length
  uint32_t lightType;       // RB_LIGHT_* = rb::LightType
  float lightPosition[3];   // point and spot lights, TLAS space
  float lightRadius;        // point and spot lights; 0 = hard shadows
  float spotDirection[3];   // from the light, unit length
  float cosSpotOuterAngle;
  float tanAngularRadius;  // directional light; 0 = hard shadows
  float range;             // point and spot lights; 0 = unlimited
  uint32_t raysPerPixel;
  uint32_t launchOverTiles;  // 1 = the launch covers the tile classifier's list, 0 = the image
  uint32_t convergedTiles;   // classifier: 1 = skip the tiles the tile state marks converged
};
static_assert(sizeof(ShadowConstants) == 228);
RB_ASSERT_OFFSET(ShadowConstants, gbuffer, 0);
RB_ASSERT_OFFSET(ShadowConstants, lightDirection, 160);
RB_ASSERT_OFFSET(ShadowConstants, lightType, 172);
RB_ASSERT_OFFSET(ShadowConstants, lightPosition, 176);
RB_ASSERT_OFFSET(ShadowConstants, lightRadius, 188);
RB_ASSERT_OFFSET(ShadowConstants, spotDirection, 192);
RB_ASSERT_OFFSET(ShadowConstants, cosSpotOuterAngle, 204);
RB_ASSERT_OFFSET(ShadowConstants, tanAngularRadius, 208);
RB_ASSERT_OFFSET(ShadowConstants, range, 212);
RB_ASSERT_OFFSET(ShadowConstants, raysPerPixel, 216);
RB_ASSERT_OFFSET(ShadowConstants, launchOverTiles, 220);
RB_ASSERT_OFFSET(ShadowConstants, convergedTiles, 224);

struct AoConstants {
  GBufferConstants gbuffer;
  float range;
  uint32_t raysPerPixel;
  uint32_t estimator;       // RB_AO_* = rb::AoEstimator
  uint32_t halfResolution;  // 1 = one sample per 2x2 block into the half-resolution image
};
static_assert(sizeof(AoConstants) == 176);
RB_ASSERT_OFFSET(AoConstants, gbuffer, 0);
RB_ASSERT_OFFSET(AoConstants, range, 160);
RB_ASSERT_OFFSET(AoConstants, raysPerPixel, 164);
RB_ASSERT_OFFSET(AoConstants, estimator, 168);
RB_ASSERT_OFFSET(AoConstants, halfResolution, 172);

struct ReflectionConstants {
  GBufferConstants gbuffer;
  float sunDirection[3];  // towards the sun, unit length
  float roughnessThreshold;
  float sunRadiance[3];
  float ambientIntensity;
  float skyRadiance[3];
  uint32_t raysPerPixel;
  uint32_t lightCount;
  uint32_t lightCandidates;
  uint32_t halfResolution;       // 1 = one sample per 2x2 block into the half-resolution image
  uint32_t changedBoxCount;      // ReflectionSettings::changedBoxes + relitBoxes at changedBoxes; 0 = none
  VkDeviceAddress changedBoxes;  // ReflectionChangedBox[] in a host-visible ring (reflection_pass.cpp)
  float sunCacheRoughness;       // pixels at least this rough read the sun from the screen; > 1 = none
  uint32_t pad1;
};
static_assert(sizeof(ReflectionConstants) == 240);
RB_ASSERT_OFFSET(ReflectionConstants, gbuffer, 0);
RB_ASSERT_OFFSET(ReflectionConstants, sunDirection, 160);
RB_ASSERT_OFFSET(ReflectionConstants, roughnessThreshold, 172);
RB_ASSERT_OFFSET(ReflectionConstants, sunRadiance, 176);
RB_ASSERT_OFFSET(ReflectionConstants, ambientIntensity, 188);
RB_ASSERT_OFFSET(ReflectionConstants, skyRadiance, 192);
RB_ASSERT_OFFSET(ReflectionConstants, raysPerPixel, 204);
RB_ASSERT_OFFSET(ReflectionConstants, lightCount, 208);
RB_ASSERT_OFFSET(ReflectionConstants, lightCandidates, 212);
RB_ASSERT_OFFSET(ReflectionConstants, halfResolution, 216);
RB_ASSERT_OFFSET(ReflectionConstants, changedBoxCount, 220);
RB_ASSERT_OFFSET(ReflectionConstants, changedBoxes, 224);
RB_ASSERT_OFFSET(ReflectionConstants, sunCacheRoughness, 232);

struct UpsampleConstants {
  GBufferConstants gbuffer;  // the traced pass's: full-resolution size, the frame that chose the samples
  float roughnessThreshold;  // reflections: rougher pixels have no reflection (a = 0)
  uint32_t pad[3];
};
static_assert(sizeof(UpsampleConstants) == 176);
RB_ASSERT_OFFSET(UpsampleConstants, gbuffer, 0);
RB_ASSERT_OFFSET(UpsampleConstants, roughnessThreshold, 160);

struct PrimaryConstants {
  float eye[3];
  float tMin;
  float right[3];  // pre-scaled by tan(fovY / 2) * aspect ratio
  float tMax;
  float up[3];  // pre-scaled by tan(fovY / 2)
  uint32_t width;
  float forward[3];
  uint32_t height;
  uint32_t flags;  // RB_GB_ALPHA_TEST or 0
  uint32_t frameIndex;
  uint32_t pad0, pad1;
};
static_assert(sizeof(PrimaryConstants) == 80);
RB_ASSERT_OFFSET(PrimaryConstants, eye, 0);
RB_ASSERT_OFFSET(PrimaryConstants, tMin, 12);
RB_ASSERT_OFFSET(PrimaryConstants, right, 16);
RB_ASSERT_OFFSET(PrimaryConstants, tMax, 28);
RB_ASSERT_OFFSET(PrimaryConstants, up, 32);
RB_ASSERT_OFFSET(PrimaryConstants, width, 44);
RB_ASSERT_OFFSET(PrimaryConstants, forward, 48);
RB_ASSERT_OFFSET(PrimaryConstants, height, 60);
RB_ASSERT_OFFSET(PrimaryConstants, flags, 64);
RB_ASSERT_OFFSET(PrimaryConstants, frameIndex, 68);

struct PrimaryShadingConstants {
  PrimaryConstants camera;
  float sunDirection[3];  // towards the sun, unit length
  float ambientIntensity;
  float sunRadiance[3];
  uint32_t lightCount;
  float skyRadiance[3];
  uint32_t lightCandidates;
};
static_assert(sizeof(PrimaryShadingConstants) == 128);
RB_ASSERT_OFFSET(PrimaryShadingConstants, camera, 0);
RB_ASSERT_OFFSET(PrimaryShadingConstants, sunDirection, 80);
RB_ASSERT_OFFSET(PrimaryShadingConstants, ambientIntensity, 92);
RB_ASSERT_OFFSET(PrimaryShadingConstants, sunRadiance, 96);
RB_ASSERT_OFFSET(PrimaryShadingConstants, lightCount, 108);
RB_ASSERT_OFFSET(PrimaryShadingConstants, skyRadiance, 112);
RB_ASSERT_OFFSET(PrimaryShadingConstants, lightCandidates, 124);

struct ManyLightConstants {
  GBufferConstants gbuffer;
  uint32_t lightCount;
  uint32_t mode;  // RB_ML_*
  uint32_t raysPerPixel;
  uint32_t candidates;
  uint32_t tiles[2];
  uint32_t pad0, pad1;
};
static_assert(sizeof(ManyLightConstants) == 192);
RB_ASSERT_OFFSET(ManyLightConstants, lightCount, 160);
RB_ASSERT_OFFSET(ManyLightConstants, mode, 164);
RB_ASSERT_OFFSET(ManyLightConstants, raysPerPixel, 168);
RB_ASSERT_OFFSET(ManyLightConstants, candidates, 172);
RB_ASSERT_OFFSET(ManyLightConstants, tiles, 176);

struct AdaptivePlanConstants {
  uint32_t size[2];
  uint32_t budget;    // most rays this frame (UINT32_MAX = no cap)
  float uniformRays;  // > 0: the budget is this many rays per surface pixel (under the cap)
  uint32_t minRays;
  uint32_t maxRays;
  uint32_t frameIndex;
  uint32_t pad0;
  uint32_t tileSize[2];  // tile granularity: the tile in pixels
};
static_assert(sizeof(AdaptivePlanConstants) == 40);
RB_ASSERT_OFFSET(AdaptivePlanConstants, budget, 8);
RB_ASSERT_OFFSET(AdaptivePlanConstants, uniformRays, 12);
RB_ASSERT_OFFSET(AdaptivePlanConstants, minRays, 16);
RB_ASSERT_OFFSET(AdaptivePlanConstants, maxRays, 20);
RB_ASSERT_OFFSET(AdaptivePlanConstants, frameIndex, 24);
RB_ASSERT_OFFSET(AdaptivePlanConstants, tileSize, 32);

struct DenoiseConstants {
  float inverseProjection[16];
  float viewToWorld[3][4];  // as GBufferConstants::viewToWorld
  float previousViewProjection[16];
  float cameraDelta[3];  // current camera position - previous camera position
  float depthSigma;
  uint32_t size[2];
  uint32_t flags;             // RB_DN_*
  uint32_t atrousStep;        // a-trous pass
  uint32_t maxHistoryFrames;  // temporal pass
  float wAtDepthOne;
  float normalPower;
  float signalRaysPerPixel;  // 0 = unknown
  float convergedNoise;      // scalar: DenoiseSettings::convergedNoise
  float roughnessThreshold;  // converged reflection tiles: ReflectionSettings::roughnessThreshold
  float resetFrames;         // scalar temporal pass: DenoiseSettings::resetFrames resolved (at least 1)
};
static_assert(sizeof(DenoiseConstants) == 236);
RB_ASSERT_OFFSET(DenoiseConstants, inverseProjection, 0);
RB_ASSERT_OFFSET(DenoiseConstants, viewToWorld, 64);
RB_ASSERT_OFFSET(DenoiseConstants, previousViewProjection, 112);
RB_ASSERT_OFFSET(DenoiseConstants, cameraDelta, 176);
RB_ASSERT_OFFSET(DenoiseConstants, depthSigma, 188);
RB_ASSERT_OFFSET(DenoiseConstants, size, 192);
RB_ASSERT_OFFSET(DenoiseConstants, flags, 200);
RB_ASSERT_OFFSET(DenoiseConstants, atrousStep, 204);
RB_ASSERT_OFFSET(DenoiseConstants, maxHistoryFrames, 208);
RB_ASSERT_OFFSET(DenoiseConstants, wAtDepthOne, 212);
RB_ASSERT_OFFSET(DenoiseConstants, normalPower, 216);
RB_ASSERT_OFFSET(DenoiseConstants, signalRaysPerPixel, 220);
RB_ASSERT_OFFSET(DenoiseConstants, convergedNoise, 224);
RB_ASSERT_OFFSET(DenoiseConstants, roughnessThreshold, 228);
RB_ASSERT_OFFSET(DenoiseConstants, resetFrames, 232);

struct ConvergedTileConstants {
  DenoiseConstants denoise;
  uint32_t pad;  // std430 rounds the nested struct up to its 16-byte alignment (240)
  uint32_t minFrames;
  float maxNoise;
  uint32_t refreshPeriod;
  uint32_t frameIndex;
};
static_assert(sizeof(ConvergedTileConstants) == 256);
RB_ASSERT_OFFSET(ConvergedTileConstants, denoise, 0);
RB_ASSERT_OFFSET(ConvergedTileConstants, minFrames, 240);
RB_ASSERT_OFFSET(ConvergedTileConstants, maxNoise, 244);
RB_ASSERT_OFFSET(ConvergedTileConstants, refreshPeriod, 248);
RB_ASSERT_OFFSET(ConvergedTileConstants, frameIndex, 252);

struct ClusterBoundsConstants {
  uint64_t positions;  // device addresses
  uint64_t indices;
  uint64_t clusterAreas;
  uint32_t positionStride;
  uint32_t positionFormat;  // RB_POSITION_*
  uint32_t indexType;       // RB_INDEX_*
  uint32_t triangleCount;
  uint32_t firstCluster;
  uint32_t pad0;
};
static_assert(sizeof(ClusterBoundsConstants) == 48);
RB_ASSERT_OFFSET(ClusterBoundsConstants, positions, 0);
RB_ASSERT_OFFSET(ClusterBoundsConstants, indices, 8);
RB_ASSERT_OFFSET(ClusterBoundsConstants, clusterAreas, 16);
RB_ASSERT_OFFSET(ClusterBoundsConstants, positionStride, 24);
RB_ASSERT_OFFSET(ClusterBoundsConstants, positionFormat, 28);
RB_ASSERT_OFFSET(ClusterBoundsConstants, indexType, 32);
RB_ASSERT_OFFSET(ClusterBoundsConstants, triangleCount, 36);
RB_ASSERT_OFFSET(ClusterBoundsConstants, firstCluster, 40);

struct ChangeMaskConstants {
  GBufferConstants gbuffer;  // the frame's camera and layout (cameraToTlas: the boxes' space)
  uint32_t boxes[2];         // device address of the ChangeBox array, TLAS space
  uint32_t boxCount;
  uint32_t masks;           // RB_CHANGE_* bits: the masks written
  float lightDirection[3];  // shadows: towards a directional light
  uint32_t lightType;       // RB_LIGHT_*
  float lightPosition[3];   // shadows: a point or spot light, TLAS space
  float aoRange;            // AO: how far an occluder counts
  float lightSpread;        // tan(angular radius) of a directional light, radius of a point or spot
  uint32_t reactive;        // 1 = the engine's reactive mask is set in every mask too
  uint32_t pad[2];
};
static_assert(sizeof(ChangeMaskConstants) == 224);
RB_ASSERT_OFFSET(ChangeMaskConstants, boxes, 160);
RB_ASSERT_OFFSET(ChangeMaskConstants, boxCount, 168);
RB_ASSERT_OFFSET(ChangeMaskConstants, masks, 172);
RB_ASSERT_OFFSET(ChangeMaskConstants, lightDirection, 176);
RB_ASSERT_OFFSET(ChangeMaskConstants, lightType, 188);
RB_ASSERT_OFFSET(ChangeMaskConstants, lightPosition, 192);
RB_ASSERT_OFFSET(ChangeMaskConstants, aoRange, 204);
RB_ASSERT_OFFSET(ChangeMaskConstants, lightSpread, 208);
RB_ASSERT_OFFSET(ChangeMaskConstants, reactive, 212);

#undef RB_ASSERT_OFFSET

// The enumerations the shaders test, by their public names.
static_assert(RB_LIGHT_DIRECTIONAL == uint32_t(LightType::Directional));
static_assert(RB_LIGHT_POINT == uint32_t(LightType::Point));
static_assert(RB_LIGHT_SPOT == uint32_t(LightType::Spot));
static_assert(RB_AO_BINARY == uint32_t(AoEstimator::Binary));
static_assert(RB_AO_DISTANCE_WEIGHTED == uint32_t(AoEstimator::DistanceWeighted));
static_assert(RB_CLUSTER_TRIANGLES == kRefitClusterTriangles);

// Checks the description (names the offending field) and fills the camera and G-buffer part of `out`.
// `passName` prefixes messages.
// The G-buffer images against the hand-over contract (gbuffer.h, "Images"): sampled-read layouts, and the usage
// and aspect the engine states. Called by fillGBufferConstants; HybridEffects calls it before recording anything.
Status validateGBufferImages(const GBufferDesc& gbuffer, const char* passName);
Status fillGBufferConstants(const GBufferDesc& gbuffer, const TlasInfo& tlas, uint64_t frame, const char* passName,
                            GBufferConstants& out);

// One image handed over like a G-buffer image (gbuffer.h, "Images"; validateGBufferImages checks each with it): a
// sampled-read layout, and where the engine states them, SAMPLED usage and the depth or colour aspect alone. `name`
// starts the message. Returns "" when it holds, else the message.
std::string checkImage(const GBufferImage& image, const std::string& name, bool depth);

// The world-space camera position: GBufferDesc::cameraPosition, or the translation of inverse(view).
void cameraPosition(const GBufferDesc& gbuffer, double out[3]);

VkImageLayout readLayout(const GBufferImage& image);

// Where the passes read roughness (rbRoughness, shaders/pass_inputs.glsl): the normal's .w when
// GBufferDesc::roughnessInNormalW, else the roughness image's .x. The denoiser and converged reflection tiles read it
// the same way, so that they agree with the pass on which pixels have a reflection.
inline bool roughnessInImage(const GBufferDesc& g) { return !g.roughnessInNormalW && g.roughnessMetalness.view; }
// The image that holds it.
inline const GBufferImage& roughnessImage(const GBufferDesc& g) {
  return roughnessInImage(g) ? g.roughnessMetalness : g.normal;
}

}  // namespace rb
