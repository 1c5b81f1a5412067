#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Ambient occlusion on G-buffer surfaces: n cosine-weighted rays over the hemisphere around the normal,
// limited to range R. Output = the open fraction AO = (1/pi) * integral of V_R(p, w) cos(theta) dw, estimated
// as the mean over cosine-weighted directions (1 = fully open).
//   binary:            a ray that hits within R contributes 0, else 1
//   distance-weighted: a hit at distance t contributes t / R (occluders fade out towards the range)
// At half resolution (pc.halfResolution) the launch is one invocation per 2x2 block, each tracing for the pixel of
// its block that half_resolution.glsl picks this frame and writing the half-resolution image at its own index.
// The body of the variants ao.rgen (pc.raysPerPixel rays everywhere) and ao_adaptive.rgen (RB_ADAPTIVE_RAYS: each
// pixel's rays come from the plan of adaptive_rays.glsl; a pixel given none keeps its reprojected history mean), and
// of ao_tiles.rgen and ao_adaptive_tiles.rgen (RB_AO_TILE_LIST, converged tiles, full resolution only): the launch
// covers the tile classifier's list (ao_classify.comp); the tiles it left out already hold their outputs. The
// variants are rows of shaders/variants.cmake.
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform AoPushConstants { AoConstants pc; };
#include "half_resolution.glsl"
#include "pass_inputs.glsl"
#include "adaptive_rays.glsl"
#include "ray_counters.glsl"
#include "reset_rays.glsl"
#ifdef RB_AO_TILE_LIST
#include "shadow_tiles.glsl"
#endif

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RB_BINDING_DEPTH) uniform sampler2D gDepth;
layout(set = 0, binding = RB_BINDING_NORMAL) uniform sampler2D gNormal;
layout(set = 0, binding = RB_BINDING_GEOMETRIC_NORMAL) uniform sampler2D gGeometricNormal;
layout(set = 0, binding = RB_AO_BINDING_OUTPUT, r16f) uniform writeonly image2D outAo;

// Payload: -1 = occluded at unknown distance, 0 = open (miss shader), > 0 = hit distance (closest hit).
layout(location = 0) rayPayloadEXT float hitT;

void main() {
  const bool halfRes = pc.halfResolution != 0u;
#ifdef RB_AO_TILE_LIST
  uvec2 launch = rbShadowListedPixel(gl_LaunchIDEXT.xy);
#else
  uvec2 launch = gl_LaunchIDEXT.xy;
#endif
  if (any(greaterThanEqual(launch, halfRes ? rbHalfResSize(pc.gbuffer.size) : pc.gbuffer.size))) return;
  uvec2 pixel = halfRes ? rbHalfResTracedPixel(launch, pc.gbuffer.frameIndex, pc.gbuffer.size) : launch;
  ivec2 ip = ivec2(pixel);
  ivec2 target = ivec2(launch);  // the output texel: the pixel, or at half resolution its sample
  float depth = texelFetch(gDepth, ip, 0).r;
  if (rbIsSky(depth)) {
    imageStore(outAo, target, vec4(1.0));
    return;
  }
  vec3 n = rbDecodeNormal(texelFetch(gNormal, ip, 0), rbNormalEncoding());
  vec3 ng = (pc.gbuffer.flags & RB_GB_GEOMETRIC_NORMAL) != 0u
                ? rbDecodeNormal(texelFetch(gGeometricNormal, ip, 0), rbNormalEncoding())
                : n;
  vec3 facing;
  vec3 origin = rbRayOrigin(pixel, depth, ng, facing);
  if (dot(n, facing) < 0.0) n = -n;  // a shading normal pointing into the surface: use the visible side
#ifdef RB_ADAPTIVE_RAYS
  const vec2 plan = texelFetch(rayPlan, ip, 0).xy;
  const uint count = uint(plan.x);
  if (count == 0u) {
    imageStore(outAo, target, vec4(plan.y));
    return;
  }
#else
  const uint count = rbResetRayCount(ip, max(pc.raysPerPixel, 1u));
#endif
  bool weighted = pc.estimator == RB_AO_DISTANCE_WEIGHTED;
  float range = pc.range;
  uint seed = rbPcg(pixel.x + pc.gbuffer.size.x * pixel.y + rbPcg(pc.gbuffer.frameIndex ^ 0x9e3779b9u));
  float jitter = rbToUnit(seed);
  float rotation = rbToUnit(rbPcg(seed)) * 2.0 * RB_PI;
  uint flags = (pc.gbuffer.flags & RB_GB_ALPHA_TEST) != 0u ? gl_RayFlagsNoneEXT : gl_RayFlagsOpaqueEXT;
  if (!weighted) flags |= gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT;
  float open = 0.0;
  for (uint i = 0u; i < count; ++i) {
    vec3 dir = rbCosineHemisphere(n, rbFibonacciDisk(i, count, jitter, rotation));
    // Below the geometric surface a ray would hit its own triangle: mirror it back above.
    float below = dot(dir, facing);
    if (below < 0.0) dir = normalize(dir - 2.0 * below * facing);
    hitT = -1.0;
    traceRayEXT(tlas, flags, 0xFF, 0, 0, 0, origin, 0.0, dir, range, 0);
    if (hitT == 0.0) {
      open += 1.0;
    } else if (weighted && hitT > 0.0) {
      open += clamp(hitT / range, 0.0, 1.0);
    }
  }
  imageStore(outAo, target, vec4(open / float(count)));
  rbCountRays(pixel, count);
}
