// The numbers the SDK's C++ and its GLSL must agree on: descriptor bindings, flag bits, enumerations and the ray
// counters. Only #defines, so the one file is included by both (sdk/src/trace/pass_constants.h and the shaders); the
// C++ side static_asserts the enumerations against the public enums.
#ifndef RAYBRIDGE_SHADER_INTERFACE_GLSL
#define RAYBRIDGE_SHADER_INTERFACE_GLSL

// Set 0 of every G-buffer ray tracing pass (shadow, AO, reflection) starts with these (PassCore::commonBindings).
#define RB_BINDING_TLAS 0
#define RB_BINDING_DEPTH 1
#define RB_BINDING_NORMAL 2
#define RB_BINDING_GEOMETRIC_NORMAL 3  // the normal image again when the G-buffer has no geometric normal
#define RB_BINDING_RAY_COUNTERS 4
// The reactive mask (HybridEffects: the effect's change mask), or the depth image again without one: where it is set
// (.r > 0.5, RB_GB_REACTIVE) the pixel's history restarts, and it traces GBufferConstants::resetRays rays; where .r
// is above RB_REACTIVE_FOLLOW_UP alone (a change's follow-up, below) it traces them and keeps its history.
#define RB_BINDING_REACTIVE 13
// Reactive mask levels. Above RB_REACTIVE_RESTART: the history restarts. Above RB_REACTIVE_FOLLOW_UP and at most
// RB_REACTIVE_RESTART: a follow-up pixel (a history restarted in one of the last frames): it traces the reset rays, and
// the scalar temporal pass adds them to its history as DenoiseSettings::resetFrames frames. The change masks write
// RB_REACTIVE_FOLLOW_UP_VALUE there (R8: 102 / 255).
#define RB_REACTIVE_RESTART 0.5
#define RB_REACTIVE_FOLLOW_UP 0.25
#define RB_REACTIVE_FOLLOW_UP_VALUE 0.4
// Pass-specific bindings of set 0.
#define RB_SHADOW_BINDING_VISIBILITY 5
#define RB_SHADOW_BINDING_HIT_DISTANCE 6  // only in the module that writes it (shadow_distance.rgen)
#define RB_SHADOW_BINDING_TILES 9         // the tile classifier's list and trace arguments (shadow_tiles.glsl)
#define RB_SHADOW_BINDING_TILE_STATE 12   // classifier only: per tile, the converged-tile state (shadow_converged.glsl)
#define RB_AO_BINDING_OUTPUT 5
// AoSettings::schedule.convergedTiles: the AO pass's tile list and tile state, at the shadow pass's bindings (the same
// layouts: shadow_tiles.glsl, shadow_converged.glsl).
#define RB_AO_BINDING_TILES RB_SHADOW_BINDING_TILES
#define RB_AO_BINDING_TILE_STATE RB_SHADOW_BINDING_TILE_STATE
#define RB_REFLECTION_BINDING_ROUGHNESS_METALNESS 5  // the normal image again when roughness is in normal.w
#define RB_REFLECTION_BINDING_RADIANCE 6
#define RB_REFLECTION_BINDING_LIGHTS 10  // the ManyLightPass's light list (GpuLight[]), read by the hits
// ReflectionFrame::sunVisibility, read by the hits (the depth image again without one: then never read).
#define RB_REFLECTION_BINDING_SUN_VISIBILITY 9
// Its surface test (rb::kReflectionSunCacheDistanceTolerance, kReflectionSunCacheMinNormalCos in reflection_pass.h).
#define RB_REFLECTION_SUN_CACHE_DISTANCE_TOLERANCE 0.01
#define RB_REFLECTION_SUN_CACHE_MIN_NORMAL_COS 0.9
// ReflectionSettings::schedule.convergedTiles: the tile state (rgb_converged.glsl), at the shadow pass's binding.
#define RB_REFLECTION_BINDING_TILE_STATE RB_SHADOW_BINDING_TILE_STATE
// Adaptive rays (the AO and shadow passes' adaptive ray generation modules): the plan of adaptive_rays.glsl.
#define RB_BINDING_RAY_PLAN 11
// Every pass whose rays can hit non-opaque geometry (shadow, AO, reflection) also has the TLAS's shading
// records, the material table and the texture set (alpha testing in the any-hit shaders, shading in reflections).
#define RB_BINDING_SHADING_RECORDS 7
#define RB_BINDING_MATERIALS 8
#define RB_SET_TEXTURES 1  // binding 0: the engine's textures, bindless (MaterialTable)
// ManyLightPass: its ray tracing pass (set 0 also has the common bindings, shading records and materials) and its
// tile-culling compute pass.
#define RB_ML_BINDING_LIGHTS 5      // GpuLight[], TLAS space
#define RB_ML_BINDING_TILES 6       // per tile: count (RB_ML_TILE_OVERFLOW = all lights), packed 16-bit indices
#define RB_ML_BINDING_IRRADIANCE 9  // rgba16f output
#define RB_ML_BINDING_TILE_STATE RB_SHADOW_BINDING_TILE_STATE  // ManyLightSettings::schedule.convergedTiles (rgb_converged.glsl)
#define RB_ML_CULL_BINDING_DEPTH 0
#define RB_ML_CULL_BINDING_LIGHTS 1
#define RB_ML_CULL_BINDING_TILES 2
#define RB_ML_TILE_SIZE 16
#define RB_ML_MAX_TILE_LIGHTS 256
#define RB_ML_TILE_UINTS (1 + RB_ML_MAX_TILE_LIGHTS / 2)
#define RB_ML_TILE_OVERFLOW 0xFFFFFFFFu
// The primary-ray (first trace) pass; it also has RB_BINDING_RAY_COUNTERS, RB_BINDING_SHADING_RECORDS,
// RB_BINDING_MATERIALS and the texture set.
#define RB_PRIMARY_BINDING_TLAS 0
#define RB_PRIMARY_BINDING_HIT_DISTANCE 1
#define RB_PRIMARY_BINDING_HIT_IDS 2
// The PrimaryShadingPass: RB_BINDING_TLAS, RB_BINDING_RAY_COUNTERS, RB_BINDING_SHADING_RECORDS, RB_BINDING_MATERIALS,
// the texture set, and these.
#define RB_PRIMARY_SHADING_BINDING_RADIANCE 1
#define RB_PRIMARY_SHADING_BINDING_DISTANCE 2
#define RB_PRIMARY_SHADING_BINDING_LIGHTS 10  // the ManyLightPass's light list (GpuLight[]), read by the hits
// The denoiser's temporal pass.
#define RB_TEMPORAL_BINDING_DEPTH 0
#define RB_TEMPORAL_BINDING_MOTION 1  // the depth image again without motion vectors
#define RB_TEMPORAL_BINDING_SIGNAL 2
#define RB_TEMPORAL_BINDING_HISTORY_IN 3
#define RB_TEMPORAL_BINDING_DISTANCE_IN 4
#define RB_TEMPORAL_BINDING_HISTORY_OUT 5
#define RB_TEMPORAL_BINDING_DISTANCE_OUT 6
#define RB_TEMPORAL_BINDING_VALUE_OUT 7  // rg: the value and the variance of its noise
#define RB_TEMPORAL_BINDING_FINAL_OUT 8  // r: the denoiser's output, written with RB_DN_TEMPORAL_FINAL
#define RB_TEMPORAL_BINDING_REACTIVE 9   // the reactive mask, or the depth image again without one
// The denoiser's a-trous pass.
#define RB_ATROUS_BINDING_DEPTH 0
#define RB_ATROUS_BINDING_NORMAL 1
#define RB_ATROUS_BINDING_SIGNAL_IN 2
#define RB_ATROUS_BINDING_SIGNAL_OUT 3  // rg: value, variance (denoise_atrous.comp); r: the output (_final.comp)
#define RB_ATROUS_BINDING_TEMPORAL 4    // denoise_atrous_final.comp: the temporal result the shift starts from
#define RB_ATROUS_BINDING_HISTORY 5     // denoise_atrous_final.comp: this frame's history (.y: its frames)
// HybridEffects' change masks (change_masks.comp): one r8 storage image per mask; a mask not written is bound to one
// that is (never touched: its RB_CHANGE_* bit is off).
#define RB_CHANGE_BINDING_DEPTH 0
#define RB_CHANGE_BINDING_REACTIVE 1  // the engine's reactive mask, or the depth image again without one
#define RB_CHANGE_BINDING_SHADOWS 2
#define RB_CHANGE_BINDING_AO 3
#define RB_CHANGE_BINDING_LOCAL_LIGHTS 4
#define RB_CHANGE_BINDING_REFLECTIONS 5
// The masks (ChangeMaskConstants::masks) and the effects a change box concerns (ChangeBox::effects).
#define RB_CHANGE_SHADOWS 1u
#define RB_CHANGE_AO 2u
#define RB_CHANGE_LOCAL_LIGHTS 4u
#define RB_CHANGE_REFLECTIONS 8u
// ChangeBox::effects flag: a box of one of the last frames' changes (HybridEffectsDesc::resetFollowUpFrames). Its
// pixels get RB_REACTIVE_FOLLOW_UP_VALUE, not 1, unless a box of this frame changes them.
#define RB_CHANGE_FOLLOW_UP 16u
// ChangeBox::effects flag: where geometry was before the change (a moved, deformed or vanished instance's old box, or
// the engine's box). A surface seen through it (the segment to the camera crosses it) may be newly visible, with no
// history to reproject: its pixels get RB_REACTIVE_FOLLOW_UP_VALUE, so the effects with reset rays trace them there
// and their denoisers weigh them (a disoccluded pixel otherwise starts from one frame of the usual rays).
#define RB_CHANGE_REVEALS 32u
// Boxes a frame's list holds at most (rb::kMaxChangeBoxes, change_tracker.h).
#define RB_CHANGE_MAX_BOXES 256
// The depth-aware upsample of half-resolution AO and reflections (upsample_depth_aware.glsl).
#define RB_UPSAMPLE_BINDING_DEPTH 0
#define RB_UPSAMPLE_BINDING_NORMAL 1
#define RB_UPSAMPLE_BINDING_ROUGHNESS_METALNESS 2  // reflections; the normal image again when roughness is in normal.w
#define RB_UPSAMPLE_BINDING_SAMPLES 3              // the half-resolution image the pass traced into
#define RB_UPSAMPLE_BINDING_OUTPUT 4               // the pass's full-resolution output

// The adaptive ray planning dispatches (adaptive_estimate.comp, adaptive_allocate.comp, adaptive_allocate_tiles.comp).
#define RB_ADAPTIVE_BINDING_DEPTH 0
#define RB_ADAPTIVE_BINDING_MOTION 1    // the depth image again without motion vectors
#define RB_ADAPTIVE_BINDING_HISTORY 2   // the denoiser's history of last frame (mean, frames)
#define RB_ADAPTIVE_BINDING_DISTANCE 3  // the denoiser's view distances of last frame
#define RB_ADAPTIVE_BINDING_WEIGHTS 4   // rg16f: reprojected mean, weight
#define RB_ADAPTIVE_BINDING_COUNTERS 5  // RbPlanCounters
#define RB_ADAPTIVE_BINDING_PLAN 6      // rg16f: rays, reprojected mean
#define RB_ADAPTIVE_BINDING_REACTIVE 7  // the reactive mask, or the depth image again without one

// GBufferConstants::flags: what the G-buffer description says.
#define RB_GB_REVERSED_Z 1u
#define RB_GB_OCTAHEDRAL 2u
#define RB_GB_GEOMETRIC_NORMAL 4u
#define RB_GB_ROUGHNESS_IN_NORMAL_W 8u
#define RB_GB_ROUGHNESS_IMAGE 16u
#define RB_GB_ALBEDO_IMAGE 32u
#define RB_GB_ALPHA_TEST 64u  // the TLAS holds non-opaque geometry and a material table is bound: rays run any-hits
#define RB_GB_REACTIVE 128u   // the G-buffer has a reactive mask (RB_BINDING_REACTIVE)

// GpuMaterial::alphaMode: the values of rb::AlphaMode.
#define RB_ALPHA_OPAQUE 0u
#define RB_ALPHA_MASK 1u
#define RB_ALPHA_BLEND 2u

// ShadowConstants::lightType: the values of rb::LightType.
#define RB_LIGHT_DIRECTIONAL 0u
#define RB_LIGHT_POINT 1u
#define RB_LIGHT_SPOT 2u

// The shadow pass's tile classifier: tiles of RB_SHADOW_TILE_SIZE^2 pixels (one workgroup each), and the uints
// before the tile list (a VkTraceRaysIndirectCommandKHR, padded to 16 bytes).
#define RB_SHADOW_TILE_SIZE 8
#define RB_SHADOW_TILE_HEADER_UINTS 4
// Converged-tile skipping (ShadowSettings::schedule.convergedTiles): one uint of state per tile. Bits 0-15: frames left
// before the tile may be skipped again (set when a refresh found a change); then what this frame does with it.
#define RB_TILE_HOLD_MASK 0xFFFFu
#define RB_TILE_SKIP_CONVERGED 0x10000u  // converged: not traced, its pixels already hold their kept-history marks
#define RB_TILE_REFRESH 0x20000u         // converged, but traced this frame to check its history still holds
// Reflections only (rgb_converged.comp): bits 18-31 hold how far the view has turned at the tile's pixels
// from the views its history holds, in units of RB_TILE_DRIFT_UNIT of a glossy lobe's width (see there).
#define RB_TILE_DRIFT_SHIFT 18u
#define RB_TILE_DRIFT_MAX 0x3FFFu
#define RB_TILE_DRIFT_UNIT (1.0 / 4096.0)
// The converged-tile dispatches (shadow_converged.comp, shadow_converged_check.comp).
#define RB_CONVERGED_BINDING_DEPTH 0
#define RB_CONVERGED_BINDING_MOTION 1  // the depth image again without motion vectors
#define RB_CONVERGED_BINDING_HISTORY 2   // the denoiser's latest history (mean, frames)
#define RB_CONVERGED_BINDING_DISTANCE 3  // its view distances
#define RB_CONVERGED_BINDING_NOISE 4     // its latest temporal result: .g = the variance of the mean's noise
#define RB_CONVERGED_BINDING_STATE 5     // the tile state buffer
#define RB_CONVERGED_BINDING_VISIBILITY 6  // storage (shadow_converged.comp) / sampled (the check)
#define RB_CONVERGED_BINDING_HIT_DISTANCE 7  // shadow_converged.comp, with ShadowPassDesc::outputHitDistance
// RGB signals (rgb_converged.comp, rgb_converged_check.comp: reflections, local lights): HISTORY is the RGB history
// (rgb mean, a frames), DISTANCE its surface image (view distance, variance of one frame's colour), VISIBILITY the
// pass's output, and:
#define RB_CONVERGED_BINDING_ROUGHNESS 8  // the roughness image (.x), or the normal image (.w)
#define RB_CONVERGED_BINDING_COUNTERS 9   // rgb_converged.comp: the pass's ray counters (tiles, rays saved)
#define RB_CONVERGED_BINDING_REACTIVE 10  // the reactive mask, or the depth image again without one

// ManyLightConstants::mode: the values of rb::ManyLightMode.
#define RB_ML_STOCHASTIC 0u
#define RB_ML_EXACT 1u

// AoConstants::estimator: the values of rb::AoEstimator.
#define RB_AO_BINARY 0u
#define RB_AO_DISTANCE_WEIGHTED 1u

// DenoiseConstants::flags.
#define RB_DN_REVERSED_Z 1u
#define RB_DN_OCTAHEDRAL 2u
#define RB_DN_HISTORY 4u  // last frame's history is valid (temporal pass)
#define RB_DN_MOTION 8u   // the G-buffer has motion vectors (temporal pass)
#define RB_DN_TEMPORAL_FINAL 16u  // scalar temporal pass: no a-trous step follows, write the output too
// Scalar temporal pass: the signal may hold kept-history marks, -1 - v for a pixel the shadow pass did not trace
// because its tile had converged (denoise_noise.glsl): it keeps its history (v, the reprojected mean) unchanged.
#define RB_DN_KEPT_MARKS 32u
// The G-buffer has a reactive mask (GBufferDesc::reactiveMask): a pixel whose .r exceeds 0.5 finds no history
// (rbDnFindHistory), in the temporal passes and in every reader that must agree with them.
#define RB_DN_REACTIVE 0x40u
// Temporal passes: history whose neighbourhood mean disagrees with this frame's by more than the noise explains is
// shortened (rbDnHistoryTrust, rbDnRgbHistoryTrust): a moved object, shadow or light is not dragged behind.
#define RB_DN_ANTI_LAG 0x80u
// Scalar a-trous final step: a pixel in the first frames of its history (DenoiseSettings::shortHistoryFilter) is
// filtered harder (rbDnYouth, denoise_noise.glsl).
#define RB_DN_SHORT_HISTORY 0x800u

// Half-resolution tracing (AoConstants/ReflectionConstants::halfResolution): sample (i, j) of frame f traces for
// G-buffer pixel (2i + x, 2j + y), clamped to the image, with (x, y) = (0,0), (1,1), (1,0), (0,1) for f mod 4 = 0..3:
// every pixel of a 2x2 block once in 4 frames, diagonal neighbours first (shaders/half_resolution.glsl).
#define RB_HALF_RES_OFFSET_X(frame) ((6u >> ((frame)&3u)) & 1u)
#define RB_HALF_RES_OFFSET_Y(frame) ((10u >> ((frame)&3u)) & 1u)

// ClusterBoundsConstants::positionFormat.
#define RB_POSITION_RGB32F 0u
#define RB_POSITION_RG32F 1u
#define RB_POSITION_RGBA32F 2u
#define RB_POSITION_RGBA16F 3u
#define RB_POSITION_RG16F 4u
#define RB_POSITION_RGBA16_SNORM 5u
#define RB_POSITION_RG16_SNORM 6u
#define RB_POSITION_RGBA8_SNORM 7u
// ClusterBoundsConstants::indexType.
#define RB_INDEX_U32 0u
#define RB_INDEX_U16 1u
#define RB_INDEX_NONE 2u
// Triangles per cluster, the workgroup size of blas_cluster_bounds.comp (rb::kRefitClusterTriangles).
#define RB_CLUSTER_TRIANGLES 64

// Rays are counted into RB_RAY_COUNTER_SLOTS counters, one per pixel of a 64x64 tile: neighbouring invocations
// (one warp or subgroup) never add to the same address, so the atomics do not serialise (PassMetrics).
#define RB_RAY_COUNTER_SLOTS 4096
#define RB_RAY_COUNTER_SLOT(x, y) (((x) & 63u) | (((y) & 63u) << 6))
// Any-hit invocations are counted the same way, in the RB_RAY_COUNTER_SLOTS counters after the ray counters.
// Then RB_RAY_COUNTER_TILE_UINTS more: the tiles a classifier traced and skipped, and padding that keeps each
// frame's counters a multiple of 256 bytes (the largest minStorageBufferOffsetAlignment).
#define RB_RAY_COUNTER_TILE_UINTS 64

#endif
