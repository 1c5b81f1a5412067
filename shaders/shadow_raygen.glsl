#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Shadow rays from G-buffer surfaces towards a directional, point or spot light. Hard: one ray to the light's
// centre. Soft: n rays over the light's disk (stratified Fibonacci spiral, rotated per pixel and frame).
// No ray for sky pixels, surfaces facing away from the light, or pixels outside a spot cone or light range
// (rbShadowPixel, shared with the tile classifier). With the classifier the launch covers its tile list
// (pc.launchOverTiles); the tiles it left out already hold their outputs. With RB_ADAPTIVE_RAYS (shadow_adaptive.rgen)
// each traced pixel's ray count comes from the adaptive plan (adaptive_rays.glsl). The body of the variants
// shadow.rgen, shadow_distance.rgen and shadow_adaptive.rgen (rows of shaders/variants.cmake).
#include "raybridge_pass_constants.glsl"
layout(push_constant) uniform ShadowPushConstants { ShadowConstants pc; };
#include "adaptive_rays.glsl"
#include "ray_counters.glsl"
#include "reset_rays.glsl"
#include "shadow_pixel.glsl"
#include "shadow_tiles.glsl"

// RB_WRITE_HIT_DISTANCE (set for shadow_distance.rgen) adds the occluder-distance output. A separate module
// rather than a specialization constant: the binding must not exist at all when the image is not allocated.
#ifdef RB_WRITE_HIT_DISTANCE
const bool kWriteHitDistance = true;
#else
const bool kWriteHitDistance = false;
#endif

layout(set = 0, binding = RB_BINDING_TLAS) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = RB_SHADOW_BINDING_VISIBILITY, r16f) uniform writeonly image2D outVisibility;
#ifdef RB_WRITE_HIT_DISTANCE
layout(set = 0, binding = RB_SHADOW_BINDING_HIT_DISTANCE, r32f) uniform writeonly image2D outHitDistance;
#endif

// Payload: -1 = occluded (set before tracing), 0 = reached the light (miss shader), > 0 = occluder distance.
layout(location = 0) rayPayloadEXT float hitT;

void main() {
  uvec2 pixel = pc.launchOverTiles != 0u ? rbShadowListedPixel(gl_LaunchIDEXT.xy) : gl_LaunchIDEXT.xy;
  if (any(greaterThanEqual(pixel, pc.gbuffer.size))) return;
  ivec2 ip = ivec2(pixel);
  ShadowPixel sp = rbShadowPixel(pixel);
  float visibility = rbShadowUntracedVisibility(sp.kind);
  float nearest = 0.0;
  uint rays = 0u;
  if (sp.kind == RB_SHADOW_PIXEL_TRACE) {
    vec3 origin = sp.origin;
    vec3 toLight = sp.toLight;
    bool directional = pc.lightType == RB_LIGHT_DIRECTIONAL;
    // The light's extent: a directional light's disk (as a slope) or a point or spot light's sphere.
    float spread = directional ? pc.tanAngularRadius : pc.lightRadius;
#ifdef RB_ADAPTIVE_RAYS
    const vec2 plan = texelFetch(rayPlan, ip, 0).xy;
    const uint count = uint(plan.x);
    const float historyMean = plan.y;
#else
    const uint count = rbResetRayCount(ip, max(pc.raysPerPixel, 1u));
    const float historyMean = 0.0;  // never read: every traced pixel gets a ray
#endif
    uint seed = rbPcg(pixel.x + pc.gbuffer.size.x * pixel.y + rbPcg(pc.gbuffer.frameIndex));
    float jitter = rbToUnit(seed);
    float rotation = rbToUnit(rbPcg(seed)) * 2.0 * RB_PI;
    vec3 t, b;
    rbBasis(toLight, t, b);
    uint visible = 0u;
    // Without the distance output any occluder will do: stop at the first and skip the hit shader.
    // Opaque fast path unless the TLAS has non-opaque geometry (alpha-tested by the any-hit shader).
    uint flags = (pc.gbuffer.flags & RB_GB_ALPHA_TEST) != 0u ? gl_RayFlagsNoneEXT : gl_RayFlagsOpaqueEXT;
    if (!kWriteHitDistance) flags |= gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT;
    nearest = 1e30;
    for (uint i = 0u; i < count; ++i) {
      vec3 dir;
      float tMax;
      if (spread > 0.0) {
        vec2 d = count == 1u ? vec2(0.0) : rbFibonacciDisk(i, count, jitter, rotation);
        if (directional) {
          dir = normalize(toLight + spread * (d.x * t + d.y * b));
          tMax = 1e30;
        } else {
          vec3 target = pc.lightPosition + spread * (d.x * t + d.y * b);
          dir = target - origin;
          tMax = length(dir);
          dir /= tMax;
          tMax *= 0.999;
        }
      } else {
        dir = toLight;
        tMax = directional ? 1e30 : 0.999 * length(pc.lightPosition - origin);
      }
      hitT = -1.0;  // occluded unless the miss shader runs
      traceRayEXT(tlas, flags, 0xFF, 0, 0, 0, origin, 0.0, dir, tMax, 0);
      if (hitT == 0.0) {
        ++visible;
      } else if (hitT > 0.0) {
        nearest = min(nearest, hitT);
      }
    }
    rays = count;
    // A pixel the adaptive plan gave no ray keeps its reprojected history mean.
    visibility = count == 0u ? historyMean : float(visible) / float(count);
    if (nearest == 1e30) nearest = 0.0;
  }
  imageStore(outVisibility, ip, vec4(visibility));
#ifdef RB_WRITE_HIT_DISTANCE
  imageStore(outHitDistance, ip, vec4(nearest));
#endif
  if (rays != 0u) rbCountRays(pixel, rays);
}
