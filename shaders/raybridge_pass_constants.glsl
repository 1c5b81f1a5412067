// The push constants of every SDK pass, one struct per pass. Each is mirrored field by field by the struct of the
// same name in sdk/src/trace/pass_constants.h, which static_asserts the size and every offset written here (std430,
// the layout of push constants). A shader declares its pass's block as
//   layout(push_constant) uniform ShadowPushConstants { ShadowConstants pc; };
// All fit the 256 bytes every device allows.
#ifndef RAYBRIDGE_PASS_CONSTANTS_GLSL
#define RAYBRIDGE_PASS_CONSTANTS_GLSL

#include "raybridge_shader_interface.glsl"

// The camera and the G-buffer's layout, shared by the G-buffer passes (shadow, AO, reflection). 160 bytes.
struct GBufferConstants {
  mat4 inverseProjection;  //   0
  mat3 viewToWorld;        //  64: rotation part of inverse(view), normalised columns (16 bytes apart)
  vec3 cameraToTlas;       // 112: the camera position in the TLAS's space
  float depthQuantum;      // 124: one step of the stored depth value; 0 = float depth (one ulp, in the shader)
  uvec2 size;              // 128: width, height in pixels
  uint flags;              // 136: RB_GB_*
  uint frameIndex;         // 140: the noise seed
  float wAtDepthOne;       // 144: w of inverse(projection) * (x, y, 1, 1), formed in double on the host
  uint resetRays;          // 148: RaySchedule::resetRays where the reactive mask is set (RB_GB_REACTIVE); 0 = none
  uint pad1;               // 152
  uint pad2;               // 156
};

// ShadowPass. 228 bytes.
struct ShadowConstants {
  GBufferConstants gbuffer;  //   0
  vec3 lightDirection;       // 160: towards a directional light, unit length
  uint lightType;            // 172: RB_LIGHT_*
  vec3 lightPosition;        // 176: of a point or spot light, in the TLAS's space
  float lightRadius;         // 188: of a point or spot light's sphere; 0 = hard shadows
  vec3 spotDirection;        // 192: from a spot light along its axis, unit length
  float cosSpotOuterAngle;   // 204
  float tanAngularRadius;    // 208: of a directional light's disk; 0 = hard shadows
  float range;               // 212: of a point or spot light; 0 = unlimited
  uint raysPerPixel;         // 216
  uint launchOverTiles;      // 220: 1 = the launch covers the tile classifier's list (shadow_tiles.glsl)
  uint convergedTiles;       // 224: classifier: 1 = skip the tiles the tile state marks RB_TILE_SKIP_CONVERGED
};

// AoPass. 176 bytes.
struct AoConstants {
  GBufferConstants gbuffer;  //   0
  float range;               // 160: occluders further than this do not count
  uint raysPerPixel;         // 164
  uint estimator;            // 168: RB_AO_*
  uint halfResolution;       // 172: 1 = one sample per 2x2 block into the half-resolution image (half_resolution.glsl)
};

// ReflectionPass. 240 bytes.
struct ReflectionConstants {
  GBufferConstants gbuffer;  //   0
  vec3 sunDirection;         // 160: towards the sun, unit length
  float roughnessThreshold;  // 172: rougher surfaces get no reflection rays
  vec3 sunRadiance;          // 176
  float ambientIntensity;    // 188: scales skyRadiance as the ambient light of hit points
  vec3 skyRadiance;          // 192: what rays that escape see
  uint raysPerPixel;         // 204
  uint lightCount;           // 208: local lights lighting hits (RB_REFLECTION_BINDING_LIGHTS); 0 = none
  uint lightCandidates;      // 212: lights weighed per hit to pick the one it traces a shadow ray to
  uint halfResolution;       // 216: 1 = one sample per 2x2 block into the half-resolution image (half_resolution.glsl)
  uint changedBoxCount;      // 220: boxes at changedBoxes (ReflectionSettings::changedBoxes + relitBoxes); 0 = none
  uvec2 changedBoxes;        // 224: their device address (RbReflectionChangedBox[], reflection_changes.glsl)
  // 232: pixels at least this rough read their hits' sun visibility from RB_REFLECTION_BINDING_SUN_VISIBILITY where
  // the hit is on screen (reflect.rchit); above 1 = none (no image given)
  float sunCacheRoughness;
  uint pad1;                 // 236
};

// The depth-aware upsample of half-resolution AO and reflections (upsample_depth_aware.glsl). 176 bytes.
struct UpsampleConstants {
  GBufferConstants gbuffer;  //   0: the traced pass's: full-resolution size, and the frame that chose the samples
  float roughnessThreshold;  // 160: reflections: rougher pixels have no reflection (a = 0), as in reflect.rgen
  uint pad0;                 // 164
  uint pad1;                 // 168
  uint pad2;                 // 172
};

// ManyLightPass (its tile culling and its rays). 192 bytes.
struct ManyLightConstants {
  GBufferConstants gbuffer;  //   0
  uint lightCount;           // 160
  uint mode;                 // 164: RB_ML_*
  uint raysPerPixel;         // 168: Stochastic
  uint candidates;           // 172: Stochastic, per ray
  uvec2 tiles;               // 176: tile grid size
  uint pad0;                 // 184
  uint pad1;                 // 188
};

// PrimaryRayPass. 80 bytes. The ray through pixel (x, y) counted from the top-left, through the pixel centre:
//   dir = normalize(forward + ndcX * right - ndcY * up), ndc in [-1, 1].
struct PrimaryConstants {
  vec3 eye;      //   0
  float tMin;    //  12
  vec3 right;    //  16: pre-scaled by tan(fovY / 2) * aspect ratio
  float tMax;    //  28
  vec3 up;       //  32: pre-scaled by tan(fovY / 2)
  uint width;    //  44
  vec3 forward;  //  48: unit length
  uint height;   //  60
  uint flags;       //  64: RB_GB_ALPHA_TEST or 0
  uint frameIndex;  //  68: Context::frameIndex(), the BLEND noise seed
  uint pad0;        //  72
  uint pad1;        //  76
};

// PrimaryShadingPass. 128 bytes: the camera of the PrimaryRayPass, then the hits' lighting (hit_shading.glsl).
struct PrimaryShadingConstants {
  PrimaryConstants camera;  //   0: flags = RB_GB_ALPHA_TEST or 0, frameIndex = the noise seed
  vec3 sunDirection;        //  80: towards the sun, unit length
  float ambientIntensity;   //  92: scales skyRadiance as the ambient light of hit points
  vec3 sunRadiance;         //  96
  uint lightCount;          // 108: local lights lighting hits (RB_PRIMARY_SHADING_BINDING_LIGHTS); 0 = none
  vec3 skyRadiance;         // 112: what rays that miss see
  uint lightCandidates;     // 124: lights weighed per hit to pick the one it traces a shadow ray to
};

// The denoiser's temporal and a-trous passes. 232 bytes.
struct DenoiseConstants {
  mat4 inverseProjection;       //   0
  mat3 viewToWorld;             //  64: as GBufferConstants::viewToWorld
  mat4 previousViewProjection;  // 112: previous frame: camera-relative world -> clip (rotation-only view)
  vec3 cameraDelta;             // 176: current camera position - previous camera position
  float depthSigma;             // 188
  uvec2 size;                   // 192: width, height in pixels
  uint flags;                   // 200: RB_DN_*
  uint atrousStep;              // 204: a-trous: the spacing of the kernel's taps in pixels
  uint maxHistoryFrames;        // 208: temporal: the most frames accumulated
  float wAtDepthOne;            // 212: as GBufferConstants::wAtDepthOne
  float normalPower;            // 216
  float signalRaysPerPixel;     // 220: rays per pixel of the noisy signal; 0 = unknown
  float convergedNoise;         // 224: scalar: noise standard deviation under which the value passes unfiltered
  float roughnessThreshold;     // 228: converged reflection tiles: the reflection pass's (rougher = no reflection)
  float resetFrames;            // 232: scalar temporal: the frames a reactive pixel's new value counts as (>= 1)
};

// The converged-tile dispatches (shadow_converged.glsl, rgb_converged.glsl): the denoiser's reprojection, then
// the test.
// 256 bytes.
struct ConvergedTileConstants {
  DenoiseConstants denoise;  //   0: historyReprojection(); signalRaysPerPixel = the shadow rays per pixel
  uint minFrames;            // 240: a converged pixel's history holds at least this many frames
  float maxNoise;            // 244: and the standard deviation of its measured noise is below this
  uint refreshPeriod;        // 248: a converged tile is still traced once in this many frames
  uint frameIndex;           // 252: which tiles refresh this frame
};

// The allocation step of adaptive rays (adaptive_allocate.comp, adaptive_allocate_tiles.comp). 40 bytes.
struct AdaptivePlanConstants {
  uvec2 size;         //  0: width, height in pixels
  uint budget;        //  8: most rays this frame (0xFFFFFFFF = no cap)
  float uniformRays;  // 12: > 0: the budget is this many rays per surface pixel (under the cap)
  uint minRays;       // 16: every surface pixel's rays while the budget allows
  uint maxRays;       // 20: no pixel gets more
  uint frameIndex;    // 24: the rounding noise's seed
  uint pad0;          // 28
  uvec2 tileSize;     // 32: adaptive_allocate_tiles.comp: the tile in pixels (powers of two, at most 16)
};

// HybridEffects' change masks (change_masks.comp): where the SDK knows the world changed this frame. 224 bytes.
struct ChangeMaskConstants {
  GBufferConstants gbuffer;  //   0: the frame's camera and layout (cameraToTlas: the boxes' space)
  uvec2 boxes;               // 160: device address of ChangeBox[boxCount] (change_masks.comp), TLAS space
  uint boxCount;             // 168
  uint masks;                // 172: RB_CHANGE_* bits: the masks written
  vec3 lightDirection;       // 176: shadows: towards a directional light, unit length
  uint lightType;            // 188: RB_LIGHT_*
  vec3 lightPosition;        // 192: shadows: a point or spot light, TLAS space
  float aoRange;             // 204: AO: how far an occluder counts
  float lightSpread;         // 208: shadows: tan(angular radius) of a directional light, radius of a point or spot
  uint reactive;             // 212: 1 = the engine's reactive mask (.r > 0.5) is set in every mask too
  uint pad0;                 // 216
  uint pad1;                 // 220
};

// The refit-quality measure of dynamic BLASes (blas_cluster_bounds.comp). 48 bytes.
struct ClusterBoundsConstants {
  uvec2 positions;      //  0: device address of vertex 0's position
  uvec2 indices;        //  8: device address of the first index (4-byte aligned); unused for RB_INDEX_NONE
  uvec2 clusterAreas;   // 16: device address of this dispatch's first output float
  uint positionStride;  // 24: bytes, a multiple of 4
  uint positionFormat;  // 28: RB_POSITION_*
  uint indexType;       // 32: RB_INDEX_*
  uint triangleCount;   // 36: of the whole mesh
  uint firstCluster;    // 40: of this dispatch (dispatches are split at the workgroup count limit)
  uint pad0;            // 44
};

#endif
